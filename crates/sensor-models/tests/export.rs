//! Map export: binary round trip, no panics on mutated files, PGM/YAML and PNG contents.
#![allow(clippy::unwrap_used)] // test code: a panic is the failure report

use nalgebra::{Point2, Point3, Vector3};
use proptest::prelude::*;
use raypath_geometry::{Grid2, Grid3, Range, Ray2, Ray3};
use raypath_sensor_models::export::{
    MapFile, MapKind, MapPicture, RosMapOptions, StoredStats, UNKNOWN_PIXEL, map_image,
    picture_values, write_png, write_ros_map,
};
use raypath_sensor_models::{DenseStats2, DenseStats3, MappingConfig, SensorModelError};

fn small_map_2d() -> DenseStats2 {
    let grid = Grid2::new(Point2::new(-1.0, -2.0), 0.25, [12, 9]).unwrap();
    let mut stats = DenseStats2::new(grid);
    let config = MappingConfig::default();
    for i in 0..40 {
        let angle = f64::from(i) * 0.15;
        let range = if i % 7 == 0 {
            Range::NoReturn
        } else {
            Range::Hit(0.3 + 0.05 * f64::from(i))
        };
        stats.insert_ray(
            &Ray2::from_angle(Point2::new(0.4, 0.1), angle, range),
            &config,
        );
    }
    stats
}

fn small_file() -> MapFile {
    MapFile {
        kind: MapKind::DecayRate,
        posterior: true,
        mapping: MappingConfig::default(),
        stats: StoredStats::Planar(small_map_2d()),
    }
}

#[test]
fn binary_round_trip_2d_and_3d() {
    let file = small_file();
    let bytes = file.to_bytes();
    assert_eq!(bytes.len(), 160 + 16 * 12 * 9 + 4);
    assert_eq!(&bytes[..8], b"RAYPMAP\0");
    let back = MapFile::from_bytes(&bytes, "mem").unwrap();
    assert_eq!(back, file);

    let grid = Grid3::new(Point3::new(0.0, 0.0, 0.0), 0.5, [6, 5, 4]).unwrap();
    let mut stats = DenseStats3::new(grid);
    let ray = Ray3::new(
        Point3::new(0.2, 0.3, 0.4),
        Vector3::new(1.0, 0.7, 0.3),
        Range::Hit(2.2),
    );
    stats.insert_ray(&ray.unwrap(), &MappingConfig::default());
    let file3 = MapFile {
        kind: MapKind::Reflection,
        posterior: false,
        mapping: MappingConfig {
            include_no_returns: false,
            ..Default::default()
        },
        stats: StoredStats::Spatial(stats),
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("map.rpm");
    file3.write_file(&path).unwrap();
    assert_eq!(MapFile::read_file(&path).unwrap(), file3);
}

#[test]
fn clear_errors_with_offsets() {
    let bytes = small_file().to_bytes();
    let check = |bytes: &[u8], offset: u64, needle: &str| match MapFile::from_bytes(bytes, "m.rpm")
    {
        Err(SensorModelError::Format {
            name,
            offset: at,
            reason,
        }) => {
            assert_eq!(name, "m.rpm");
            assert_eq!(at, offset, "{reason}");
            assert!(reason.contains(needle), "{reason}");
        }
        other => panic!("expected a format error, got {other:?}"),
    };
    let mut bad = bytes.clone();
    bad[0] = b'X';
    check(&bad, 0, "magic");
    let mut bad = bytes.clone();
    bad[8] = 2;
    check(&bad, 8, "version");
    let mut bad = bytes.clone();
    bad[12] = 4;
    check(&bad, 12, "dimensions");
    let mut bad = bytes.clone();
    bad[200] ^= 1;
    check(&bad, bytes.len() as u64 - 4, "checksum");
    check(&bytes[..bytes.len() - 1], 88, "need");
    check(&bytes[..100], 0, "shorter");
    // A huge cell count is rejected before allocating.
    let mut bad = bytes.clone();
    bad[48..56].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(MapFile::from_bytes(&bad, "m.rpm").is_err());
}

/// Bitwise CRC-32 (IEEE), independent of the crate's table version.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Truncated and randomly mutated files give errors (or a valid map), never panics.
    /// Half of the cases repair the checksum so that the field checks behind it run.
    #[test]
    fn mutated_files_never_panic(
        cut in 0usize..4000,
        flips in proptest::collection::vec((0usize..2000, any::<u8>()), 0..6),
        repair_crc in any::<bool>(),
    ) {
        let mut bytes = small_file().to_bytes();
        for (at, value) in flips {
            // Mostly the header, where the structure is.
            let len = if at % 2 == 0 { 160 } else { bytes.len() - 4 };
            bytes[at % len] = value;
        }
        if repair_crc {
            let body = bytes.len() - 4;
            let crc = crc32(&bytes[..body]);
            bytes[body..].copy_from_slice(&crc.to_le_bytes());
        }
        if cut < bytes.len() {
            bytes.truncate(cut);
        }
        if let Ok(file) = MapFile::from_bytes(&bytes, "fuzz") {
            // Whatever parses writes a file that reads back the same (lengths are rounded
            // to the fixed-point resolution, so bytes may differ once).
            let again = MapFile::from_bytes(&file.to_bytes(), "again");
            prop_assert!(again.as_ref().ok() == Some(&file));
        }
    }
}

#[test]
fn ros_map_and_png() {
    let stats = small_map_2d();
    let values = picture_values(&stats, MapPicture::Reflection);
    let observed = values.iter().filter(|v| v.is_some()).count();
    assert!(observed > 0 && observed < values.len());
    let dir = tempfile::tempdir().unwrap();
    let (pgm, yaml) = write_ros_map(
        &dir.path().join("intel"),
        stats.grid(),
        &values,
        &RosMapOptions::default(),
    )
    .unwrap();
    let pgm_bytes = std::fs::read(&pgm).unwrap();
    let header = b"P5\n# raypath map\n12 9\n255\n";
    assert_eq!(&pgm_bytes[..header.len()], header);
    let pixels = &pgm_bytes[header.len()..];
    assert_eq!(pixels.len(), 12 * 9);
    // Top row is the largest y: pixel (row 0, col c) is cell (c, 8).
    for col in 0..12 {
        let expected = match values[8 * 12 + col] {
            Some(p) => (255.0 * (1.0 - p)).round() as u8,
            None => UNKNOWN_PIXEL,
        };
        assert_eq!(pixels[col], expected);
    }
    let yaml_text = std::fs::read_to_string(&yaml).unwrap();
    for line in [
        "image: intel.pgm",
        "resolution: 0.25",
        "origin: [-1, -2, 0.0]",
        "negate: 0",
        "occupied_thresh: 0.65",
        "free_thresh: 0.196",
        "mode: trinary",
    ] {
        assert!(
            yaml_text.lines().any(|l| l == line),
            "missing {line:?} in\n{yaml_text}"
        );
    }
    let png = dir.path().join("intel.png");
    let decay = picture_values(&stats, MapPicture::DecayRate);
    write_png(&png, stats.grid(), &decay).unwrap();
    let image = image::open(&png).unwrap().to_luma8();
    assert_eq!(image.dimensions(), (12, 9));
    assert_eq!(image.as_raw(), &map_image(stats.grid(), &decay).unwrap());
    assert!(map_image(stats.grid(), &decay[1..]).is_err());
}
