//! Runs PPE (preset `kitti`) on real KITTI frames projected to 64 × 2083 range images, as
//! `cargo xtask eval synpeb` does, and prints per frame the planes, the per-ray radial RMSE,
//! the time and a fingerprint of the segmentation (to compare two builds of PPE).
//!
//! `RAYPATH_DATA=… cargo run --release -p raypath-planes --example ppe_kitti -- [SEQ…]`
//! (sequences under `$RAYPATH_DATA/kitti/sequences`, default 00 01 04 07; frames 0–9).

use std::time::Instant;

use nalgebra::Point3;
use raypath_geometry::RingProjection;
use raypath_io::kitti::KittiSequence;
use raypath_planes::{PpeParams, extract};

/// Lasers and firings per revolution of the HDL-64E at 10 Hz (the eval's range image).
const RINGS: usize = 64;
const COLUMNS: usize = 2083;

fn main() {
    let mut seqs: Vec<String> = std::env::args().skip(1).collect();
    if seqs.is_empty() {
        seqs = ["00", "01", "04", "07"].map(String::from).to_vec();
    }
    let params = PpeParams::kitti();
    let (mut n, mut rmse, mut secs) = (0.0, 0.0, 0.0);
    for seq in seqs {
        let Some(dir) = raypath_io::data::require(format!("kitti/sequences/{seq}")) else {
            continue;
        };
        let sequence = KittiSequence::open(&dir).expect("open the sequence");
        for file in sequence.scan_files.iter().take(10) {
            let cloud = sequence.scan(file.frame).expect("scan").expect("read");
            let projection = RingProjection::new(RINGS, COLUMNS).expect("projection");
            let image = projection
                .project(&cloud, &Point3::origin())
                .expect("project");
            let organized = image.to_point_cloud(&Point3::origin());
            let t = Instant::now();
            let seg = extract(&organized, &params).expect("extract");
            let dt = t.elapsed().as_secs_f64();
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            for l in &seg.labels {
                for byte in l.unwrap_or(u32::MAX).to_le_bytes() {
                    h = (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
                }
            }
            println!(
                "{seq}/{:06}: planes {} rmse {:.2} mm steps {} labels {h:016x} {dt:.3} s",
                file.frame,
                seg.planes.len(),
                1000.0 * seg.rmse_m(),
                seg.steps
            );
            (n, rmse, secs) = (n + 1.0, rmse + seg.rmse_m(), secs + dt);
        }
    }
    let n = f64::max(n, 1.0);
    println!(
        "MEAN of {n}: rmse {:.2} mm t {:.3} s",
        1000.0 * rmse / n,
        secs / n
    );
}
