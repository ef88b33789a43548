//! Trajectory evaluation on synthetic tracks with known offsets.

#![allow(clippy::unwrap_used)]

use std::f64::consts::{FRAC_PI_2, PI};

use raypath_geometry::{Pose2, Pose3};
use raypath_localizer::eval::{
    ArcLengthIndex, EvaluationConfig, TrajectoryEvaluation, evaluate_trajectory,
    relative_motion_errors,
};
use raypath_localizer::{PoseTrack, Stamped};

/// A straight track at `speed` m/s along heading `heading`, sampled every `dt` seconds.
fn straight(heading: f64, speed: f64, duration: f64, dt: f64) -> PoseTrack<Pose2> {
    let n = (duration / dt).round() as usize;
    PoseTrack::new((0..=n).map(|i| {
        let t = i as f64 * dt;
        let d = speed * t;
        Stamped::new(t, Pose2::new(d * heading.cos(), d * heading.sin(), heading))
    }))
    .unwrap()
}

/// Every pose of `track` moved by `offset` in its own frame (x ahead, y left, θ).
fn offset(track: &PoseTrack<Pose2>, offset: Pose2) -> PoseTrack<Pose2> {
    PoseTrack::new(
        track
            .iter()
            .map(|s| Stamped::new(s.stamp_secs, s.pose * offset)),
    )
    .unwrap()
}

#[test]
fn constant_lateral_offset_on_a_straight_line() {
    let gt = straight(0.5, 1.0, 20.5, 0.1);
    let est = offset(&gt, Pose2::new(0.0, 0.3, 0.0));
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    // 20.5 m of arc length: points at 0, 1, …, 20 m.
    assert_eq!(e.points.len(), 21);
    assert_eq!(e.skipped_points, 0);
    assert!((e.length_m - 20.5).abs() < 1e-9);
    assert!((e.lateral_m.rmse - 0.3).abs() < 1e-9);
    assert!((e.lateral_m.mean - 0.3).abs() < 1e-9);
    assert!(e.lateral_m.std < 1e-9);
    assert!(e.longitudinal_m.rmse < 1e-9);
    assert!((e.position_m.rmse - 0.3).abs() < 1e-9);
    assert!((e.position_m.mean_abs - 0.3).abs() < 1e-9);
    assert!(e.heading_rad.rmse < 1e-12);
    assert!(!e.divergence.diverged());
    assert_eq!(e.divergence.fraction_of_time, 0.0);
}

#[test]
fn constant_lateral_offset_on_a_circle() {
    // Counter-clockwise circle of radius 10 m, 1 m/s, dense samples; the estimate runs 0.3 m
    // to the left (towards the centre).
    let radius = 10.0;
    let track = |r: f64| {
        PoseTrack::new((0..=2000).map(|i| {
            let t = i as f64 * 0.05;
            let a = t / radius;
            Stamped::new(t, Pose2::new(r * a.cos(), r * a.sin(), a + FRAC_PI_2))
        }))
        .unwrap()
    };
    let gt = track(radius);
    let est = track(radius - 0.3);
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    // 100 s at 1 m/s; the chords of the sampled polygon are a hair shorter than the arc
    // (99.9999 m), so the points are 0, 1, …, 99 m.
    assert!((e.length_m - 100.0).abs() < 1e-3 && e.length_m < 100.0);
    assert_eq!(e.points.len(), 100);
    assert!(
        (e.lateral_m.rmse - 0.3).abs() < 1e-3,
        "{}",
        e.lateral_m.rmse
    );
    assert!(e.longitudinal_m.rmse < 1e-3, "{}", e.longitudinal_m.rmse);
    assert!(e.heading_rad.rmse < 1e-9);
}

#[test]
fn longitudinal_and_heading_offsets() {
    // The estimate runs 0.5 s ahead at 2 m/s: 1 m longitudinal error.
    let gt = straight(-2.0, 2.0, 30.0, 0.25);
    let est = PoseTrack::new(gt.iter().map(|s| {
        let d = 2.0 * (s.stamp_secs + 0.5);
        Stamped::new(
            s.stamp_secs,
            Pose2::new(d * (-2f64).cos(), d * (-2f64).sin(), -2.0),
        )
    }))
    .unwrap();
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.points.len(), 61);
    assert!((e.longitudinal_m.mean - 1.0).abs() < 1e-9);
    assert!(e.lateral_m.rmse < 1e-9);

    let rotated = offset(&gt, Pose2::new(0.0, 0.0, -0.05));
    let e = evaluate_trajectory(&gt, &rotated, &EvaluationConfig::default()).unwrap();
    assert!((e.heading_rad.mean + 0.05).abs() < 1e-12);
    assert!((e.heading_rad.mean_abs - 0.05).abs() < 1e-12);
    assert!(e.position_m.rmse < 1e-9);
}

#[test]
fn headings_wrap_across_pi() {
    let gt = straight(PI - 0.01, 1.0, 10.0, 0.5);
    let est = offset(&gt, Pose2::new(0.0, 0.0, 0.02));
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    assert!(
        (e.heading_rad.mean - 0.02).abs() < 1e-9,
        "{}",
        e.heading_rad.mean
    );
}

#[test]
fn one_sample_per_metre_on_a_known_path_with_stops() {
    // A 4 m × 3 m rectangle (14 m) with a 5 s stop at every corner; 1 m/s while moving.
    let corners = [(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (0.0, 3.0), (0.0, 0.0)];
    let mut samples = Vec::new();
    let mut t = 0.0;
    for w in corners.windows(2) {
        let ((x0, y0), (x1, y1)): ((f64, f64), (f64, f64)) = (w[0], w[1]);
        let heading = (y1 - y0).atan2(x1 - x0);
        samples.push(Stamped::new(t, Pose2::new(x0, y0, heading)));
        t += 5.0; // standing still
        let length = (x1 - x0).hypot(y1 - y0);
        samples.push(Stamped::new(t, Pose2::new(x0, y0, heading)));
        t += length;
        samples.push(Stamped::new(t - 1e-3, Pose2::new(x1, y1, heading)));
    }
    let gt = PoseTrack::new(samples).unwrap();
    let arc = ArcLengthIndex::new(&gt);
    assert!((arc.total_m() - 14.0).abs() < 1e-12);
    let e = evaluate_trajectory(&gt, &gt, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.points.len(), 15);
    for (k, p) in e.points.iter().enumerate() {
        assert!((p.arc_length_m - k as f64).abs() < 1e-12);
    }
    // Point at 4 m is the first corner, reached at 5 + 4 − 0.001 s (not after the stop).
    let corner = &e.points[4];
    assert!(
        (corner.stamp_secs - 8.999).abs() < 1e-9,
        "{}",
        corner.stamp_secs
    );
    assert!((corner.ground_truth.x() - 4.0).abs() < 1e-12);
    // Half-metre spacing doubles the points (0, 0.5, …, 14).
    let half = EvaluationConfig {
        spacing_m: 0.5,
        ..EvaluationConfig::default()
    };
    assert_eq!(
        evaluate_trajectory(&gt, &gt, &half).unwrap().points.len(),
        29
    );
    // 10.5 m straight: points at 0 … 10 m.
    let short = straight(1.0, 1.5, 7.0, 0.1);
    let e = evaluate_trajectory(&short, &short, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.points.len(), 11);
}

#[test]
fn divergence_episodes_and_time_fraction() {
    let gt = straight(0.0, 1.0, 40.0, 0.1);
    // 10 m off during [10, 18) s and [25, 27) s.
    let est = PoseTrack::new(gt.iter().map(|s| {
        let t = s.stamp_secs;
        let off = if (10.0..18.0).contains(&t) || (25.0..27.0).contains(&t) {
            10.0
        } else {
            0.0
        };
        Stamped::new(t, s.pose * Pose2::new(0.0, off, 0.0))
    }))
    .unwrap();
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.divergence.episodes, 2);
    assert!(e.divergence.diverged());
    assert!((e.divergence.first_divergence_secs.unwrap() - 10.0).abs() < 1e-9);
    // 10 of 40 s diverged (± one point of 1 s at each of the four edges).
    assert!(
        (e.divergence.fraction_of_time - 0.25).abs() < 0.05,
        "{}",
        e.divergence.fraction_of_time
    );
    // The threshold is configurable.
    let lax = EvaluationConfig {
        divergence_threshold_m: 20.0,
        ..EvaluationConfig::default()
    };
    assert_eq!(
        evaluate_trajectory(&gt, &est, &lax)
            .unwrap()
            .divergence
            .episodes,
        0
    );
}

#[test]
fn estimates_outside_their_span_are_skipped() {
    let gt = straight(0.0, 1.0, 20.0, 0.1);
    let est = PoseTrack::new(gt.iter().filter(|s| s.stamp_secs >= 9.95)).unwrap();
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.skipped_points, 10);
    assert_eq!(e.points.len(), 11);
    let bad = EvaluationConfig {
        spacing_m: 0.0,
        ..EvaluationConfig::default()
    };
    assert!(evaluate_trajectory(&gt, &est, &bad).is_err());
}

#[test]
fn results_serialize_to_json() {
    let gt = straight(0.0, 1.0, 5.0, 0.5);
    let e = evaluate_trajectory(
        &gt,
        &offset(&gt, Pose2::new(0.1, 0.2, 0.0)),
        &EvaluationConfig::default(),
    )
    .unwrap();
    let json = serde_json::to_string(&e).unwrap();
    assert!(json.contains("\"lateral_m\"") && json.contains("\"rmse\""));
    let back: TrajectoryEvaluation = serde_json::from_str(&json).unwrap();
    // serde_json parses floats to within an ulp or so.
    assert_eq!(back.points.len(), e.points.len());
    assert!((back.lateral_m.rmse - e.lateral_m.rmse).abs() < 1e-15);
    assert!((back.position_m.mean_abs - e.position_m.mean_abs).abs() < 1e-15);
    assert_eq!(back.divergence, e.divergence);
}

#[test]
fn relative_motion_errors_ignore_a_constant_offset_and_measure_scale_drift() {
    let gt = straight(0.3, 1.0, 50.0, 0.2);
    // The whole estimate moved and turned rigidly: no relative error.
    let moved = PoseTrack::new(
        gt.iter()
            .map(|s| Stamped::new(s.stamp_secs, Pose2::new(5.0, -3.0, 1.0) * s.pose)),
    )
    .unwrap();
    let r = relative_motion_errors(&gt, &moved, 10.0, 1.0).unwrap();
    assert_eq!(r.translation_m.count, 41);
    assert!(r.translation_m.max_abs < 1e-9 && r.rotation_rad.max_abs < 1e-9);
    // 1 % too long: 0.1 m error per 10 m, drift 0.01.
    let scaled = PoseTrack::new(gt.iter().map(|s| {
        let d = 1.01 * s.stamp_secs;
        Stamped::new(
            s.stamp_secs,
            Pose2::new(d * 0.3f64.cos(), d * 0.3f64.sin(), 0.3),
        )
    }))
    .unwrap();
    let r = relative_motion_errors(&gt, &scaled, 10.0, 1.0).unwrap();
    assert!((r.translation_m.mean - 0.1).abs() < 1e-9);
    assert!((r.translation_per_m.mean - 0.01).abs() < 1e-10);
    assert!(relative_motion_errors(&gt, &scaled, -1.0, 1.0).is_err());
}

#[test]
fn se3_tracks_are_evaluated_in_the_plane() {
    let gt = PoseTrack::new((0..=100).map(|i| {
        let t = f64::from(i) * 0.1;
        Stamped::new(t, Pose3::from_xyz_rpy(t, 0.0, 0.1 * t, 0.0, -0.1, 0.0))
    }))
    .unwrap();
    // 0.25 m to the left and 2 m higher: only the lateral error counts.
    let est = PoseTrack::new(gt.iter().map(|s| {
        let p = s.pose.translation();
        Stamped::new(
            s.stamp_secs,
            Pose3::from_xyz_rpy(p.x, p.y + 0.25, p.z + 2.0, 0.0, -0.1, 0.0),
        )
    }))
    .unwrap();
    let e = evaluate_trajectory(&gt, &est, &EvaluationConfig::default()).unwrap();
    assert_eq!(e.points.len(), 11);
    assert!((e.lateral_m.rmse - 0.25).abs() < 1e-9);
    assert!(e.longitudinal_m.rmse < 1e-9 && e.heading_rad.rmse < 1e-9);
}
