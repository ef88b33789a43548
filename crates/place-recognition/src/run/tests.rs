use image::{GrayImage, Luma};

use super::*;
use crate::Frame;

/// Describes an image by its mean gray value; similarity 1 / (1 + |difference|).
#[derive(Default)]
struct MeanRecognizer {
    means: Vec<f64>,
}

impl MeanRecognizer {
    fn score(a: f64, b: f64) -> f64 {
        1.0 / (1.0 + (a - b).abs())
    }
}

impl PlaceRecognizer for MeanRecognizer {
    type Description = f64;

    fn name(&self) -> &'static str {
        "mean"
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<f64> {
        let Frame::Image(image) = frame else {
            return Err(PlaceError::UnsupportedFrame {
                method: "mean",
                frame: frame.kind(),
            });
        };
        if image.is_empty() {
            return Err(PlaceError::BadInput("empty image".into()));
        }
        let sum: f64 = image.pixels().map(|p| f64::from(p.0[0])).sum();
        Ok(sum / f64::from(image.width() * image.height()))
    }

    fn query(&self, description: &f64, before: usize) -> Vec<Candidate> {
        (0..before.min(self.means.len()))
            .map(|frame| Candidate {
                frame,
                score: Self::score(*description, self.means[frame]),
            })
            .collect()
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        self.means
            .get(index)
            .map_or_else(Vec::new, |d| self.query(d, before))
    }

    fn insert(&mut self, description: f64) {
        self.means.push(description);
    }

    fn len(&self) -> usize {
        self.means.len()
    }
}

const VALUES: [u8; 6] = [10, 50, 90, 10, 50, 91];

fn frame(t: usize) -> Result<OwnedFrame> {
    let v = VALUES
        .get(t)
        .ok_or_else(|| PlaceError::BadInput(format!("no frame {t}")))?;
    Ok(OwnedFrame::Image(GrayImage::from_pixel(4, 3, Luma([*v]))))
}

#[test]
fn online_queries_only_frames_before_the_window() {
    let mut m = MeanRecognizer::default();
    let run = run_online(&mut m, VALUES.len(), frame, 2).unwrap();
    assert_eq!(run.method, "mean");
    assert_eq!(m.len(), 6);
    let sizes: Vec<usize> = run.candidates.iter().map(Vec::len).collect();
    assert_eq!(sizes, vec![0, 0, 0, 1, 2, 3]);
    let best: Vec<Option<(usize, f64)>> = run
        .best()
        .iter()
        .map(|c| c.map(|c| (c.frame, c.score)))
        .collect();
    assert_eq!(best[3], Some((0, 1.0)));
    assert_eq!(best[4], Some((1, 1.0)));
    assert_eq!(best[5], Some((2, 0.5)));
    for list in &run.candidates {
        assert!(list.windows(2).all(|w| w[0].score >= w[1].score), "sorted");
    }
    assert_eq!(run.timings.len(), 6);
    for t in &run.timings {
        assert!(t.describe_s >= 0.0 && t.query_s >= 0.0 && t.insert_s >= 0.0);
        assert!((t.total_s - (t.describe_s + t.query_s + t.insert_s)).abs() < 1e-12);
    }
    let loops = run.loops(&LoopConfig::default()).unwrap();
    assert_eq!(loops.first().map(|l| (l.query, l.matched)), Some((3, 0)));
}

#[test]
fn kidnapped_every_frame_retrieves_itself_first() {
    let mut m = MeanRecognizer::default();
    let run = run_kidnapped(&mut m, VALUES.len(), frame, None).unwrap();
    for (i, list) in run.candidates.iter().enumerate() {
        assert_eq!(list.len(), VALUES.len());
        // Frames 0 and 3 are identical: ties go to the lowest index.
        let top = list[0];
        assert_eq!(top.score, 1.0);
        assert_eq!(top.frame, if i >= 3 && i != 5 { i - 3 } else { i });
    }
    let mut serial = MeanRecognizer::default();
    let again = run_kidnapped_serial(&mut serial, VALUES.len(), frame, Some(2)).unwrap();
    for (a, b) in run.candidates.iter().zip(&again.candidates) {
        assert_eq!(&a[..2], &b[..]);
    }
    let mean = FrameTiming::mean(&run.timings);
    assert!(mean.total_s >= mean.query_s);
}

#[test]
fn errors_carry_the_frame_and_a_used_database_is_refused() {
    let mut m = MeanRecognizer::default();
    let empty = |t: usize| -> Result<OwnedFrame> {
        if t == 2 {
            Ok(OwnedFrame::Image(GrayImage::new(0, 0)))
        } else {
            frame(t)
        }
    };
    let err = run_online(&mut m, 4, empty, 0).unwrap_err();
    assert!(err.to_string().contains("frame 2"), "{err}");
    assert!(
        run_online(&mut m, 1, frame, 0).is_err(),
        "database not empty"
    );
    let mut fresh = MeanRecognizer::default();
    assert!(
        run_kidnapped(&mut fresh, 7, frame, None).is_err(),
        "source fails at 6"
    );
}

#[test]
fn sort_puts_nan_last() {
    let mut c = vec![
        Candidate {
            frame: 4,
            score: f64::NAN,
        },
        Candidate {
            frame: 3,
            score: 0.2,
        },
        Candidate {
            frame: 1,
            score: 0.7,
        },
        Candidate {
            frame: 0,
            score: 0.2,
        },
    ];
    sort_candidates(&mut c);
    let order: Vec<usize> = c.iter().map(|c| c.frame).collect();
    assert_eq!(order, vec![1, 0, 3, 4]);
}
