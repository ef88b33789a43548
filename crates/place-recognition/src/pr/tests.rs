use super::*;

fn c(frame: usize, score: f64) -> Candidate {
    Candidate { frame, score }
}

/// Frames 0 and 2 at one place, 1 and 3 at another.
fn two_places() -> GroundTruth {
    let positions = [
        [0.0, 0.0, 0.0],
        [50.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [50.0, 1.0, 0.0],
    ];
    GroundTruth::from_positions(&positions, None, 5.0, Exclusion::none()).unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn kidnapped_known_curve() {
    let candidates = vec![
        vec![c(0, 1.0), c(2, 0.9), c(1, 0.5), c(3, 0.2)],
        vec![c(3, 0.4), c(0, 0.6)],
        vec![c(0, 0.7), c(3, 0.3)],
        vec![c(1, 0.45), c(2, f64::NAN)],
    ];
    let curve = kidnapped_pr(&candidates, &two_places()).unwrap();
    assert_eq!(curve.positives, 2);
    // Pairs by max score: (0,2) 0.9 T, (0,1) 0.6 F, (1,3) 0.45 T, (2,3) 0.3 F, (0,3) 0.2 F.
    let expected = [
        (0.9, 1.0, 0.5),
        (0.6, 0.5, 0.5),
        (0.45, 2.0 / 3.0, 1.0),
        (0.3, 0.5, 1.0),
        (0.2, 0.4, 1.0),
    ];
    assert_eq!(curve.points.len(), expected.len());
    for (p, &(t, pr, r)) in curve.points.iter().zip(&expected) {
        assert!(
            close(p.threshold, t) && close(p.precision, pr) && close(p.recall, r),
            "{p:?}"
        );
    }
    let s = curve.summary();
    assert!(close(s.recall_at_100_precision, 0.5));
    assert!(close(s.precision_at_100_recall, 2.0 / 3.0));
    assert!(close(s.max_f1, 0.8));
}

#[test]
fn kidnapped_without_full_recall_and_with_ties() {
    // (1,3) is never proposed: 100 % recall is never reached. (0,2) and (0,1) tie.
    let candidates = vec![vec![c(2, 0.5), c(1, 0.5)], vec![], vec![], vec![]];
    let curve = kidnapped_pr(&candidates, &two_places()).unwrap();
    assert_eq!(curve.points.len(), 1, "one point per distinct score");
    let s = curve.summary();
    assert_eq!(s.recall_at_100_precision, 0.0);
    assert_eq!(s.precision_at_100_recall, 0.0);
    assert!(close(s.max_f1, 0.5)); // P = 1/2, R = 1/2
}

#[test]
fn kidnapped_rejects_out_of_range_frames() {
    let candidates = vec![vec![c(9, 0.5)], vec![], vec![], vec![]];
    assert!(kidnapped_pr(&candidates, &two_places()).is_err());
    assert!(kidnapped_pr(&[], &two_places()).is_err());
}

/// 30 frames: 0..10 along x, 10..20 far away, 20..30 revisit 0..10.
fn revisit_truth() -> GroundTruth {
    let positions: Vec<[f64; 3]> = (0..30)
        .map(|t| match t {
            0..10 => [t as f64, 0.0, 0.0],
            10..20 => [t as f64, 100.0, 0.0],
            _ => [(t - 20) as f64, 0.0, 0.0],
        })
        .collect();
    let ex = Exclusion {
        frames: 5,
        seconds: 0.0,
    };
    GroundTruth::from_positions(&positions, None, 0.5, ex).unwrap()
}

fn revisit_candidates() -> Vec<Vec<Candidate>> {
    (0..30)
        .map(|t| match t {
            25 => vec![c(5, 0.5), c(15, 0.9)],
            20.. => vec![c(t - 20, 0.8), c(12, 0.1)],
            _ => vec![],
        })
        .collect()
}

#[test]
fn online_temporal_consistency_rejects_the_outlier() {
    let truth = revisit_truth();
    let curve = online_pr(&revisit_candidates(), &truth, &LoopConfig::default(), 0).unwrap();
    assert_eq!(curve.positives, 10);
    // Threshold 0.9: only the wrong 25 ↔ 15 passes and is accepted as a first loop.
    // Threshold 0.8: 20 ↔ 0 opens the chain of windows; 25 ↔ 15 is rejected.
    let got: Vec<(f64, f64, f64)> = curve
        .points
        .iter()
        .map(|p| (p.threshold, p.precision, p.recall))
        .collect();
    assert_eq!(got, vec![(0.9, 0.0, 0.0), (0.8, 1.0, 0.9)]);
    let s = curve.summary();
    assert!(close(s.recall_at_100_precision, 0.9));
    assert_eq!(s.precision_at_100_recall, 0.0);
    assert!(close(s.max_f1, 1.8 / 1.9));
}

#[test]
fn online_without_temporal_consistency_accepts_the_outlier() {
    let config = LoopConfig {
        temporal_consistency: false,
        ..LoopConfig::default()
    };
    let curve = online_pr(&revisit_candidates(), &revisit_truth(), &config, 0).unwrap();
    let last = curve.points.last().unwrap();
    assert!(close(last.precision, 0.9) && close(last.recall, 0.9));
}

#[test]
fn online_threshold_quantiles_keep_extremes() {
    let best: Vec<Option<Candidate>> = (0..1000).map(|k| Some(c(0, k as f64))).collect();
    let t = online_thresholds(&best, 5);
    assert_eq!(t, vec![999.0, 749.0, 499.0, 250.0, 0.0]);
    assert_eq!(online_thresholds(&best, 0).len(), 1000);
}
