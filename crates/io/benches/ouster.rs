//! Ouster decoding speed on the real captures of RAYPATH_DATA/ouster: frames per second and
//! pixels per second of packet decoding into destaggered images (`decode`, the
//! capture held in memory), and of the ranges-to-points conversion (`xyz`).
//!
//! Run with `RAYPATH_DATA=/path/to/data cargo bench -p raypath-io --bench ouster`; without
//! the data the benchmarks are skipped with a message.
#![allow(clippy::unwrap_used)]

use std::hint::black_box;
use std::io::Cursor;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raypath_io::ouster::{self, OusterOptions, OusterReader, SensorInfo, XyzLut};

const CAPTURES: [(&str, &str); 2] = [
    (
        "os1_128_low_data",
        "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
    ),
    ("os2_128_single", "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap"),
];

fn bench(c: &mut Criterion) {
    for (name, relative) in CAPTURES {
        let Some(pcap) = raypath_io::data::require(relative) else {
            continue;
        };
        let info = SensorInfo::read(&ouster::find_metadata(&pcap).unwrap()).unwrap();
        let bytes = std::fs::read(&pcap).unwrap();
        let read = |bytes: &[u8]| {
            OusterReader::new(
                Cursor::new(bytes.to_vec()),
                "bench.pcap",
                &info,
                OusterOptions::default(),
            )
            .unwrap()
            .collect::<Result<Vec<_>, _>>()
            .unwrap()
        };
        let frames = read(&bytes);
        let pixels = (frames.len() * info.columns_per_frame * info.pixels_per_column) as u64;

        // Time per iteration = time for all frames of the capture; pixels/s from Criterion,
        // frames/s = pixels/s ÷ (W · H).
        let mut group = c.benchmark_group("ouster_decode");
        group.throughput(Throughput::Elements(pixels));
        group.bench_function(format!("{name}_{}_frames", frames.len()), |b| {
            b.iter(|| black_box(read(black_box(&bytes))))
        });
        group.finish();

        let lut = XyzLut::new(&info).unwrap();
        let mut group = c.benchmark_group(format!("ouster_xyz_{name}"));
        group.throughput(Throughput::Elements(
            (info.columns_per_frame * info.pixels_per_column) as u64,
        ));
        group.bench_function("cloud", |b| {
            b.iter(|| black_box(lut.cloud(black_box(&frames[0])).unwrap()))
        });
        group.bench_function("lut", |b| b.iter(|| black_box(XyzLut::new(&info).unwrap())));
        group.finish();
    }
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    use super::*;
    criterion_group!(benches, bench);
}
criterion_main!(group::benches);
