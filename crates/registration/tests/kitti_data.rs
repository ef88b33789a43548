//! Registration and odometry on the real KITTI frames (RAYPATH_DATA/kitti/sequences/NN,
//! frames 0–9) against their SemanticKITTI (SuMa) poses; skipped without the data.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

mod common;

use common::pose_error;
use raypath_geometry::Pose3;
use raypath_io::data::require;
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_registration::{Odometry, OdometryConfig, RegistrationConfig, register};

const FRAMES: usize = 10;

#[test]
fn real_kitti_frames_register_to_their_poses() {
    let Some(root) = require("kitti/sequences") else {
        return;
    };
    let mut checked = 0;
    for seq in ["00", "01", "04", "07"] {
        let Some(dir) = require(root.join(seq)) else {
            continue;
        };
        // `SweepSequence` turns the camera poses into velodyne poses through `Tr`.
        let sequence = SweepSequence::open(&dir, &SweepOptions::default()).unwrap();
        let truth = sequence.reference.clone().unwrap();
        let mut odometry = Odometry::new(OdometryConfig::default()).unwrap();
        let mut previous = None;
        let (mut odo_t, mut odo_r, mut f2f_t) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..FRAMES {
            let cloud = sequence.sweep(k).unwrap();
            odometry.register_frame(&cloud).unwrap();
            if let Some(prev) = previous.replace(cloud.clone()) {
                let expected = truth[k - 1].inverse() * truth[k];
                let poses = odometry.poses();
                let (dt, dr) = pose_error(&expected, &(poses[k - 1].inverse() * poses[k]));
                odo_t.push(dt);
                odo_r.push(dr.to_degrees());
                let pair = register(
                    &cloud,
                    &prev,
                    &Pose3::identity(),
                    &RegistrationConfig::default(),
                )
                .unwrap();
                f2f_t.push(pose_error(&expected, &pair.target_from_source).0);
            }
        }
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        eprintln!(
            "{seq}: odometry mean {:.3} m max {:.3} m, {:.3}° max; frame-to-frame mean {:.3} m",
            mean(&odo_t),
            max(&odo_t),
            max(&odo_r),
            mean(&f2f_t)
        );
        // The reference is SuMa's estimate, itself good to a few centimetres: the steps of
        // 0.1–1.3 m agree to centimetres and a tenth of a degree.
        assert!(
            mean(&odo_t) < 0.04 && max(&odo_t) < 0.12,
            "{seq}: {odo_t:?}"
        );
        assert!(max(&odo_r) < 0.2, "{seq}: {odo_r:?}");
        assert!(
            mean(&f2f_t) < 0.05 && max(&f2f_t) < 0.15,
            "{seq}: {f2f_t:?}"
        );
        checked += 1;
    }
    assert!(checked > 0, "no KITTI sequence under {}", root.display());
}
