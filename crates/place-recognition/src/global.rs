//! Global (holistic) image descriptors as place recognisers (Khan 2017, §4.5.2): the
//! "vocabulary" stores one HOG or GIST descriptor per frame, and frames are compared by the
//! cosine similarity
//!
//! ```text
//! S_global(I_i, I_j) = d_iᵀ d_j / √((d_iᵀ d_i)(d_jᵀ d_j))
//! ```
//!
//! Frames become images by [`frame_image`] (a camera image as it is, a planar scan
//! rasterised, a cloud projected to its equirectangular intensity or range image).
//!
//! ## Decisions
//!
//! * The descriptors are stored one after the other in one `Vec<f32>` with their norms, so a
//!   query is one pass over contiguous memory.
//! * A zero descriptor (a constant image) has no direction: it scores 0 against every frame,
//!   and so do two descriptors of different lengths (HOG of images of different sizes).
//! * [`query_stored`](PlaceRecognizer::query_stored) scores the frame against itself 1 (its
//!   cosine, also for a zero descriptor) and lists it first; the other scores are clamped to
//!   `[−1, 1]`, so no other frame outranks it (an identical frame ties).

use raypath_geometry::lane_dot;

use crate::gist::{Gist, GistConfig};
use crate::hog::{HogConfig, hog};
use crate::{Candidate, Frame, ImageConfig, PlaceRecognizer, Result, frame_image};

/// Cosine similarity of two descriptors; 0 if either is zero or their lengths differ.
pub fn cosine_similarity(a: &[f32], b: &[f32]) -> f64 {
    if a.len() != b.len() {
        return 0.0;
    }
    let (na, nb) = (lane_dot(a, a), lane_dot(b, b));
    cosine(lane_dot(a, b), na, nb)
}

/// `ab / √(aa · bb)` clamped to `[−1, 1]`; 0 when a norm is 0.
fn cosine(ab: f32, aa: f32, bb: f32) -> f64 {
    let denominator = (f64::from(aa) * f64::from(bb)).sqrt();
    if denominator > 0.0 {
        (f64::from(ab) / denominator).clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

/// Which global descriptor.
#[derive(Clone, Debug)]
enum Method {
    Hog(HogConfig),
    Gist(Box<Gist>),
}

/// A database of global image descriptors (HOG or GIST) compared by cosine similarity
/// (Khan 2017, §4.5.2). Names: `"hog"`, `"gist"`.
#[derive(Clone, Debug)]
pub struct GlobalDescriptorDb {
    method: Method,
    image: ImageConfig,
    /// All descriptors, one after the other.
    data: Vec<f32>,
    /// Start of descriptor `i` in `data` is `starts[i]`, its end `starts[i + 1]`.
    starts: Vec<usize>,
    /// `d_iᵀ d_i`.
    norms2: Vec<f32>,
}

impl GlobalDescriptorDb {
    fn with(method: Method, image: ImageConfig) -> Self {
        Self {
            method,
            image,
            data: Vec::new(),
            starts: vec![0],
            norms2: Vec::new(),
        }
    }

    /// An empty HOG database; frames become images by `image`.
    pub fn hog(config: HogConfig, image: ImageConfig) -> Self {
        Self::with(Method::Hog(config), image)
    }

    /// An empty GIST database (prepares the Gabor bank; errors on an invalid `config`).
    pub fn gist(config: GistConfig, image: ImageConfig) -> Result<Self> {
        Ok(Self::with(
            Method::Gist(Box::new(Gist::new(config)?)),
            image,
        ))
    }

    /// The stored descriptor of frame `index`.
    pub fn descriptor(&self, index: usize) -> Option<&[f32]> {
        let (start, end) = (*self.starts.get(index)?, *self.starts.get(index + 1)?);
        Some(&self.data[start..end])
    }

    /// Cosine similarity of `d` (with `d_iᵀd_i = dd`) against the frames `0..before`.
    fn scores(&self, d: &[f32], dd: f32, before: usize) -> Vec<Candidate> {
        let n = before.min(self.len());
        (0..n)
            .map(|j| {
                let stored = &self.data[self.starts[j]..self.starts[j + 1]];
                let score = if stored.len() == d.len() {
                    cosine(lane_dot(d, stored), dd, self.norms2[j])
                } else {
                    0.0
                };
                Candidate { frame: j, score }
            })
            .collect()
    }
}

impl PlaceRecognizer for GlobalDescriptorDb {
    type Description = Vec<f32>;

    fn name(&self) -> &'static str {
        match self.method {
            Method::Hog(_) => "hog",
            Method::Gist(_) => "gist",
        }
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<Vec<f32>> {
        let image = frame_image(frame, &self.image)?;
        match &self.method {
            Method::Hog(config) => hog(&image, config),
            Method::Gist(gist) => gist.describe(&image),
        }
    }

    fn query(&self, description: &Vec<f32>, before: usize) -> Vec<Candidate> {
        self.scores(description, lane_dot(description, description), before)
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        let Some(d) = self.descriptor(index) else {
            return Vec::new();
        };
        let mut candidates = self.scores(d, self.norms2[index], before);
        if index < candidates.len() {
            candidates[index].score = 1.0;
            candidates[..=index].rotate_right(1);
        }
        candidates
    }

    fn insert(&mut self, description: Vec<f32>) {
        self.norms2.push(lane_dot(&description, &description));
        self.data.extend_from_slice(&description);
        self.starts.push(self.data.len());
    }

    fn len(&self) -> usize {
        self.norms2.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::GrayImage;

    fn scene(seed: u32) -> GrayImage {
        GrayImage::from_fn(128, 64, |x, y| {
            let v = (x * (3 + seed) + y * (7 + 2 * seed) + (x / 16) * 40 * seed) % 256;
            image::Luma([v as u8])
        })
    }

    #[test]
    fn cosine_matches_the_formula() {
        let (a, b) = (
            [1.0f32, 2.0, 3.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
            [2.0f32, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 2.0, 1.0],
        );
        let ab: f64 = a.iter().zip(&b).map(|(x, y)| f64::from(x * y)).sum();
        let (aa, bb): (f64, f64) = (
            a.iter().map(|x| f64::from(x * x)).sum(),
            b.iter().map(|x| f64::from(x * x)).sum(),
        );
        assert!((cosine_similarity(&a, &b) - ab / (aa * bb).sqrt()).abs() < 1e-6);
        assert_eq!(cosine_similarity(&a, &[0.0; 9]), 0.0);
        assert_eq!(cosine_similarity(&a, &b[..3]), 0.0);
    }

    #[test]
    fn frames_retrieve_themselves_first() {
        for mut db in [
            GlobalDescriptorDb::hog(HogConfig::default(), ImageConfig::default()),
            GlobalDescriptorDb::gist(
                GistConfig {
                    image_size: 64,
                    ..GistConfig::default()
                },
                ImageConfig::default(),
            )
            .unwrap(),
        ] {
            let images: Vec<GrayImage> =
                (0..4).map(scene).chain([GrayImage::new(128, 64)]).collect();
            for img in &images {
                let d = db.describe(&Frame::Image(img)).unwrap();
                let c = db.query(&d, db.len());
                assert_eq!(c.len(), db.len());
                db.insert(d);
            }
            assert!(["hog", "gist"].contains(&db.name()));
            for i in 0..images.len() {
                let c = db.query_stored(i, images.len());
                assert_eq!(c.len(), images.len());
                assert_eq!(
                    c[0],
                    Candidate {
                        frame: i,
                        score: 1.0
                    }
                );
                assert!(c[1..].iter().all(|o| o.score <= 1.0 && o.frame != i));
                let fresh = db.query(&db.descriptor(i).unwrap().to_vec(), images.len());
                let expect = if i == 4 { 0.0 } else { 1.0 }; // the black image's zero descriptor
                assert!(
                    (fresh[i].score - expect).abs() < 1e-5,
                    "{} frame {i}: {}",
                    db.name(),
                    fresh[i].score
                );
            }
            assert_eq!(
                db.query_stored(4, 5)
                    .iter()
                    .filter(|c| c.score != 0.0)
                    .count(),
                1
            );
            assert_eq!(db.query_stored(3, 2).len(), 2);
            assert!(db.query_stored(9, 5).is_empty());
        }
    }
}

#[cfg(test)]
mod real_data {
    use super::*;
    use crate::LidarChannel;
    use image::GrayImage;
    use raypath_geometry::PointCloud;

    /// A KITTI velodyne scan (`float32 x y z intensity`), or `None` when `RAYPATH_DATA` does
    /// not hold it.
    fn kitti(sequence: &str, frame: usize) -> Option<PointCloud> {
        let path = raypath_io::data::require(format!(
            "kitti/sequences/{sequence}/velodyne/{frame:06}.bin"
        ))?;
        let bytes = std::fs::read(&path).unwrap();
        let values: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let points = values
            .chunks_exact(4)
            .map(|p| nalgebra::Point3::new(p[0], p[1], p[2]))
            .collect();
        let intensity = values.chunks_exact(4).map(|p| p[3]).collect();
        Some(PointCloud {
            intensity: Some(intensity),
            ..PointCloud::from_points(points)
        })
    }

    /// Real KITTI scans: the next frame of sequence 00 (about 1 m on) is the most similar of
    /// the first frames of sequences 01, 04 and 07, for HOG and GIST of both lidar images; a
    /// cloud is described as its equirectangular image.
    #[test]
    fn kitti_consecutive_frames_are_most_similar() {
        let scans: Vec<PointCloud> = [("00", 0), ("00", 1), ("01", 0), ("04", 0), ("07", 0)]
            .iter()
            .filter_map(|&(s, f)| kitti(s, f))
            .collect();
        if scans.len() < 5 {
            return;
        }
        for channel in [LidarChannel::Intensity, LidarChannel::Range] {
            let image = ImageConfig {
                channel,
                ..ImageConfig::default()
            };
            let images: Vec<GrayImage> = scans
                .iter()
                .map(|s| frame_image(&Frame::Cloud(s), &image).unwrap().into_owned())
                .collect();
            let gist = GistConfig::default();
            for mut db in [
                GlobalDescriptorDb::hog(HogConfig::default(), image.clone()),
                GlobalDescriptorDb::gist(gist, image.clone()).unwrap(),
            ] {
                for img in &images {
                    let d = db.describe(&Frame::Image(img)).unwrap();
                    db.insert(d);
                }
                let from_cloud = db.describe(&Frame::Cloud(&scans[0])).unwrap();
                assert_eq!(from_cloud, db.descriptor(0).unwrap());
                let c = db.query_stored(0, scans.len());
                let best = c[1..]
                    .iter()
                    .max_by(|a, b| a.score.total_cmp(&b.score))
                    .unwrap();
                assert_eq!(best.frame, 1, "{channel:?} {}: {c:?}", db.name());
            }
        }
    }
}
