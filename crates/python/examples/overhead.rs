//! The Rust side of the Python overhead measurement (`examples/overhead.py` runs it beside
//! the same calls through the Python package): the library calls the bindings make, timed
//! without Python.
//!
//! ```text
//! cargo build --release -p raypath-python --example overhead
//! target/release/examples/overhead poles <kitti-sequence-dir> <reps>   # frame 0
//! target/release/examples/overhead slam <raw-log> <reps> [<first scans only>]
//! ```
//!
//! Prints one JSON line per repetition: `{"task", "seconds"}` of the timed section (the input
//! is read before the clock starts, as the Python side opens it before its call).

use std::path::PathBuf;
use std::time::Instant;

use _raypath::pipeline::rebuild_map;
use nalgebra::Point3;
use raypath_io::sequence::{SweepOptions, SweepSequence, read_planar};
use raypath_poles::{Preset, extract_poles};
use raypath_slam::{Slam, SlamConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage =
        "usage: overhead poles <kitti-sequence-dir> <reps> | slam <raw-log> <reps> [<scans>]";
    let (Some(task), Some(path), Some(reps)) = (args.first(), args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let path = PathBuf::from(path);
    let reps: usize = reps.parse()?;
    match task.as_str() {
        "poles" => {
            // Frame 0 of the sequence at its reference pose, as the Python side passes it.
            let sequence = SweepSequence::open(&path, &SweepOptions::default())?;
            let cloud = sequence.sweep(0)?;
            let pose = sequence.require_reference()?[0];
            let preset = Preset::kitti();
            for _ in 0..reps {
                let started = Instant::now();
                let center = Point3::from(pose.translation());
                let (poles, _) = extract_poles(&[(pose, &cloud)], &center, &preset.extraction)?;
                let seconds = started.elapsed().as_secs_f64();
                println!(
                    "{{\"task\": \"poles\", \"seconds\": {seconds}, \"poles\": {}}}",
                    poles.len()
                );
            }
        }
        "slam" => {
            let mut frames = read_planar(&path, &Default::default())?;
            if let Some(n) = args.get(3) {
                frames.truncate(n.parse()?);
            }
            for _ in 0..reps {
                let started = Instant::now();
                // `raypath.slam`'s defaults (those of `raypath slam`).
                let mut config = SlamConfig::default();
                config.matcher.map.finest_resolution_m = 0.05;
                config.filter.max_range_m = 30.0;
                let mut slam = Slam::new(config)?;
                for frame in &frames {
                    slam.process(frame)?;
                }
                let output = slam.finish()?;
                let (_, values) = rebuild_map(&frames, &output.world_from_sensor, 0.05, 30.0)?;
                let seconds = started.elapsed().as_secs_f64();
                println!(
                    "{{\"task\": \"slam\", \"seconds\": {seconds}, \"cells\": {}}}",
                    values.len()
                );
            }
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
