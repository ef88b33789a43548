//! SegComp Perceptron files and Unix compress: known answers on synthetic files that follow
//! the documented layouts, and `.Z` reference vectors made by ncompress.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_io::lzw;
use raypath_io::segcomp::{
    self, PerceptronGeometry, RasterFormat, parse_gt_ang, parse_gt_seg, parse_range_image,
};
use raypath_io::{Format, Location, summarize};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The synthetic 4 × 3 range image of `tests/data/segcomp/synth.test.1.Z`, uncompressed.
fn range_bytes() -> Vec<u8> {
    let lines = [
        "4 rows",
        "3 columns",
        "synthetic range image in the SegComp Perceptron layout",
        "made for the raypath tests",
        "line 5",
        "line 6",
        "line 7 a b",
        "line 8 a b",
        "line 9 a",
        "line 10 a b c",
    ];
    let mut bytes = format!("{}\n\n", lines.join("\n")).into_bytes();
    for i in 0..12u32 {
        bytes.extend(((i * 300 + 7) | (0xabc << 12) | (0x7 << 28)).to_be_bytes());
    }
    bytes
}

fn range_values() -> Vec<u16> {
    (0..12).map(|i| i * 300 + 7).collect()
}

const LCG_MUL: u64 = 6_364_136_223_846_793_005;
const LCG_ADD: u64 = 1_442_695_040_888_963_407;

fn lcg_symbols(n: usize, mut x: u64) -> Vec<u8> {
    (0..n)
        .map(|_| {
            x = x.wrapping_mul(LCG_MUL).wrapping_add(LCG_ADD);
            b"acgt"[((x >> 33) & 3) as usize]
        })
        .collect()
}

fn lzw_inputs() -> Vec<(&'static str, Vec<u8>)> {
    let text: String = (0..3000)
        .map(|i| format!("{} ", (i * 7919) % 1000))
        .collect();
    let mut mixed = b"the quick brown fox ".repeat(500);
    mixed.extend(lcg_symbols(10_000, 12345));
    mixed.extend(b"the quick brown fox ".repeat(100));
    vec![
        ("tobe", b"TOBEORNOTTOBEORTOBEORNOT#".to_vec()),
        ("text-b16", text.into_bytes()),
        ("mixed-b9", mixed.clone()),
        ("mixed-b12", mixed),
    ]
}

#[test]
fn lzw_decodes_ncompress_reference_files() {
    for (name, input) in lzw_inputs() {
        let packed = std::fs::read(fixture(&format!("lzw/{name}.Z"))).unwrap();
        assert!(lzw::is_compressed(&packed));
        let unpacked = lzw::decompress(&packed, 1 << 20).unwrap();
        assert_eq!(unpacked.len(), input.len(), "{name}");
        assert!(unpacked == input, "{name}: content differs");
        // Cut-off files decode to a prefix or fail; they never panic or invent data.
        for cut in [3, packed.len() / 2, packed.len() - 1] {
            if let Ok(part) = lzw::decompress(&packed[..cut], 1 << 20) {
                assert!(input.starts_with(&part), "{name} cut at {cut}");
            }
        }
    }
}

#[test]
fn lzw_matches_compress_program_when_installed() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    if Command::new("compress").arg("-V").output().is_err() {
        raypath_io::data::skip("no `compress` program (apt-get install ncompress) to compare with");
        return;
    }
    for (k, bits) in (9..=16).enumerate() {
        let mut input = lcg_symbols(5_000 + 9_000 * k, k as u64);
        input.extend(b"raypath ".repeat(200 * k));
        input.extend(
            lcg_symbols(3_000, 99)
                .iter()
                .map(|b| b.wrapping_mul(k as u8 + 1)),
        );
        let mut child = Command::new("compress")
            .args([format!("-b{bits}").as_str(), "-c", "-f"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(&input).unwrap();
        let packed = child.wait_with_output().unwrap().stdout;
        let unpacked = lzw::decompress(&packed, 1 << 24).unwrap();
        assert!(unpacked == input, "{bits} bits: content differs");
    }
}

#[test]
fn sc2cart_known_answers() {
    let g = PerceptronGeometry::default();
    // Computed by hand from the formulas of `PerceptronGeometry`'s docs, in the file's unit.
    let cases = [
        (
            (0, 0, 2000.0),
            [251.566426055160, 161.822426882470, 489.421675083153],
        ),
        (
            (255, 256, 1000.0),
            [-0.330899668271, 0.231869120451, 370.379290932587],
        ),
        (
            (511, 100, 4095.0),
            [270.997098832601, -301.833831266435, 910.751733091856],
        ),
    ];
    for ((row, col, range), want) in cases {
        let got = g.scanner_xyz(row, col, 512, 512, range);
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() < 1e-9,
                "({row}, {col}): {got} vs {want:?}"
            );
        }
        // REP-103 sensor frame in metres: x forward = Z, y left = X, z up = Y.
        let p = g.point(row, col, 512, 512, range);
        let expect = Point3::new(want[2], want[0], want[1]) * 1e-3;
        assert!((p - expect).norm() < 1e-12);
    }
    // Top-left pixel looks up and to the left; the range grows with the raw value.
    let near = g.point(0, 0, 512, 512, 100.0);
    let far = g.point(0, 0, 512, 512, 3000.0);
    assert!(near.y > 0.0 && near.z > 0.0 && far.coords.norm() > near.coords.norm());
}

#[test]
fn range_image_layout_and_cloud() {
    let image = parse_range_image(&range_bytes(), "r").unwrap();
    assert_eq!((image.rows, image.columns), (4, 3));
    assert_eq!(image.range, range_values());
    assert_eq!(image.get(3, 2), Some(11 * 300 + 7));
    assert_eq!(image.get(4, 0), None);
    assert_eq!(image.header.len(), 11);
    assert_eq!(
        image.header[2],
        "synthetic range image in the SegComp Perceptron layout"
    );
    let g = PerceptronGeometry::default();
    let cloud = image.to_cloud(&g);
    assert_eq!((cloud.width, cloud.height, cloud.len()), (3, 4, 12));
    let want = g.point(2, 1, 4, 3, f64::from(7 * 300 + 7)).cast::<f32>();
    assert_eq!(cloud.points[cloud.index(2, 1)], want);
    // The original reader's variant: the extra "line" is one byte, not a full line.
    let mut one_byte = range_bytes();
    let at = one_byte.windows(2).position(|w| w == b"\n\n").unwrap() + 1;
    one_byte[at] = b' ';
    assert_eq!(
        parse_range_image(&one_byte, "r").unwrap().range,
        range_values()
    );
}

#[test]
fn range_errors_name_line_and_byte() {
    let bytes = range_bytes();
    let err = parse_range_image(&bytes[..bytes.len() - 3], "r").unwrap_err();
    assert!(
        err.to_string()
            .contains("unexpected end of file while reading 4 × 3 pixels"),
        "{err}"
    );
    let data_start = (bytes.len() - 48) as u64;
    assert_eq!(err.location(), Location::Byte(data_start));
    let mut longer = bytes.clone();
    longer.extend([1, 2, 3, 4]);
    let err = parse_range_image(&longer, "r").unwrap_err();
    assert_eq!(err.location(), Location::Byte(data_start + 48));
    let text = String::from_utf8_lossy(&bytes).replacen("4 rows", "rows", 1);
    let err = parse_range_image(text.as_bytes(), "r").unwrap_err();
    assert_eq!(err.to_string(), "r:1: no number of rows in \"rows\"");
    let err = parse_range_image(b"4 rows\n3 columns\n", "r").unwrap_err();
    assert_eq!(err.location(), Location::Line(3));
}

#[test]
fn compressed_fixtures_read_and_summarize() {
    let range_path = fixture("segcomp/synth.test.1.Z");
    assert_eq!(Format::detect(&range_path).unwrap(), Format::SegcompRange);
    let scan = segcomp::read_perceptron(&range_path).unwrap();
    assert_eq!(scan.image, parse_range_image(&range_bytes(), "r").unwrap());
    assert_eq!(scan.cloud.len(), 12);
    let summary = summarize(&range_path).unwrap();
    assert_eq!(summary.format, "segcomp-range");
    assert_eq!(
        (summary.width, summary.height, summary.points),
        (Some(3), Some(4), Some(12))
    );
    assert_eq!(summary.extra["range_max"], 3307);
    assert!(summary.bbox.is_some());

    let seg_path = fixture("segcomp/synth.test.1.gt-seg.Z");
    assert_eq!(Format::detect(&seg_path).unwrap(), Format::SegcompGtSeg);
    let seg = segcomp::read_gt_seg(&seg_path).unwrap();
    assert_eq!(seg.format, RasterFormat::SunRaster);
    assert_eq!((seg.rows, seg.columns), (4, 3));
    assert_eq!(
        seg.labels,
        vec![10, 10, 10, 11, 11, 11, 128, 12, 12, 13, 13, 13]
    );
    assert_eq!(seg.plane_labels(), vec![10, 11, 12, 13, 128]);
    let summary = summarize(&seg_path).unwrap();
    assert_eq!(summary.format, "segcomp-gt-seg");
    assert_eq!(summary.labels, Some(vec![10, 11, 12, 13, 128]));
    assert_eq!(summary.extra["raster"], "sun-raster");

    let ang_path = fixture("segcomp/synth.test.1.gt-ang");
    assert_eq!(Format::detect(&ang_path).unwrap(), Format::SegcompGtAng);
    let summary = summarize(&ang_path).unwrap();
    assert_eq!(summary.format, "segcomp-gt-ang");
    assert_eq!(summary.extra["pairs"], 3);
    assert_eq!(summary.labels, Some(vec![10, 11, 12]));
}

fn sun_raster(kind: u32, width: u32, rows: &[Vec<u8>]) -> Vec<u8> {
    let mut pixels = Vec::new();
    for row in rows {
        pixels.extend(row);
        if width % 2 == 1 {
            pixels.push(0);
        }
    }
    let mut bytes = Vec::new();
    for word in [
        0x59a6_6a95,
        width,
        rows.len() as u32,
        8,
        pixels.len() as u32,
        kind,
        0,
        0,
    ] {
        bytes.extend(u32::to_be_bytes(word));
    }
    bytes.extend(pixels);
    bytes
}

#[test]
fn gt_seg_variants() {
    let rows = vec![vec![0u8, 10, 10], vec![11, 11, 255]];
    let want = vec![0, 10, 10, 11, 11, 255];
    let seg = parse_gt_seg(&sun_raster(1, 3, &rows), "s").unwrap();
    assert_eq!(
        (seg.rows, seg.columns, seg.labels.clone()),
        (2, 3, want.clone())
    );
    assert_eq!(seg.get(1, 2), Some(255));

    let mut pgm = b"P5\n# labels\n3 2\n255\n".to_vec();
    pgm.extend(rows.concat());
    let seg = parse_gt_seg(&pgm, "p").unwrap();
    assert_eq!(
        (seg.format, seg.labels.clone()),
        (RasterFormat::Pgm, want.clone())
    );
    let seg = parse_gt_seg(b"P2 3 2 65535\n0 10 10\n11 11 255\n", "p").unwrap();
    assert_eq!(seg.labels, want);
    let mut wide = b"P5 2 1 1000\n".to_vec();
    wide.extend([0x03, 0xe8, 0x00, 0x0a]);
    assert_eq!(parse_gt_seg(&wide, "p").unwrap().labels, vec![1000, 10]);

    let mut raw = b"2 rows\n3 columns\n".to_vec();
    raw.extend(b"x\n".repeat(8));
    raw.extend(b"\n");
    raw.extend(rows.concat());
    let seg = parse_gt_seg(&raw, "r").unwrap();
    assert_eq!(
        (seg.format, seg.labels.clone()),
        (RasterFormat::RawWithHeader, want)
    );

    // Errors name the place.
    let bytes = sun_raster(1, 3, &rows);
    let err = parse_gt_seg(&bytes[..bytes.len() - 1], "s").unwrap_err();
    assert_eq!(err.location(), Location::Byte(32));
    let mut deep = sun_raster(1, 3, &rows);
    deep[15] = 24;
    let err = parse_gt_seg(&deep, "s").unwrap_err();
    assert_eq!(
        err.to_string(),
        "s: byte 12: 24 bits per pixel; label images have 8"
    );
    let err = parse_gt_seg(b"P5 3 2 255\n\x01\x02", "p").unwrap_err();
    assert_eq!(err.location(), Location::Byte(11));
}

/// Inputs found by `cargo xtask fuzz`: errors about a cut header or cut pixels name a byte
/// inside the file (the Sun header's words are read out of order, and the PGM reader stepped
/// over the blank after maxval), and a pixel above maxval names its byte.
#[test]
fn gt_seg_errors_name_a_byte_inside_the_file() {
    let sun = sun_raster(1, 3, &[vec![0u8, 10, 10], vec![11, 11, 255]]);
    // Cut after six of the header's eight words (fuzz case 510; was byte 28 of 24).
    let err = parse_gt_seg(&sun[..24], "s").unwrap_err();
    assert_eq!(err.location(), Location::Byte(24), "{err}");
    assert!(err.to_string().contains("Sun rasterfile header"), "{err}");
    // Cut inside the fifth word (was byte 20 of 19).
    let err = parse_gt_seg(&sun[..19], "s").unwrap_err();
    assert_eq!(err.location(), Location::Byte(16), "{err}");
    // A binary PGM that ends right after its maxval (fuzz case 513; was byte 19 of 18).
    let err = parse_gt_seg(b"P5\n#-1\x00308 c\n3 2\n3", "p").unwrap_err();
    assert_eq!(err.location(), Location::Byte(18), "{err}");
    assert!(err.to_string().contains("3 × 2 PGM pixels"), "{err}");
    // Pixels above maxval (binary, text): their byte, not the whole file.
    let err = parse_gt_seg(b"P5 2 1 10\n\x05\x0b", "p").unwrap_err();
    assert_eq!(
        err.to_string(),
        "p: byte 11: pixel 1 exceeds maxval 10",
        "{err}"
    );
    let err = parse_gt_seg(b"P2 2 1 10\n5 11\n", "p").unwrap_err();
    assert_eq!(
        err.to_string(),
        "p: byte 12: pixel 1 exceeds maxval 10",
        "{err}"
    );
    // Perceptron-layout files that end with header line 10 (fuzz cases 1058 of gt-seg and
    // 4066 of range; were one byte beyond the end): the end of the file.
    let mut head = b"2 rows\n3 columns\n".to_vec();
    head.extend(b"x\n".repeat(8));
    let err = parse_gt_seg(&head, "r").unwrap_err();
    assert_eq!(err.location(), Location::Byte(head.len() as u64), "{err}");
    let err = parse_range_image(&head, "perc.test.1").unwrap_err();
    assert_eq!(err.location(), Location::Byte(head.len() as u64), "{err}");
    assert!(err.to_string().contains("0 present"), "{err}");
}

#[test]
fn gt_ang_parses_and_checks() {
    let text = "3\n10 11 90\n11 12 45\n\n10 12 135\n";
    let angles = parse_gt_ang(std::io::Cursor::new(text), "a").unwrap();
    assert_eq!(angles.pairs.len(), 3);
    assert_eq!(
        (
            angles.pairs[2].label_a,
            angles.pairs[2].label_b,
            angles.pairs[2].angle_deg
        ),
        (10, 12, 135.0)
    );
    let err = parse_gt_ang(std::io::Cursor::new("3\n10 11 90\n"), "a").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("a:3: unexpected end of file while reading entry 2 of 3"),
        "{err}"
    );
    let err = parse_gt_ang(std::io::Cursor::new("1\n10 11 90\n1 2 3\n"), "a").unwrap_err();
    assert_eq!(err.to_string(), "a:3: more entries than the 1 announced");
    let err = parse_gt_ang(std::io::Cursor::new("1\n10 11 270\n"), "a").unwrap_err();
    assert_eq!(err.location(), Location::Line(2));
    let err = parse_gt_ang(std::io::Cursor::new("1\n10 x 2\n"), "a").unwrap_err();
    assert_eq!(err.to_string(), "a:2: second label: cannot parse \"x\"");
}

#[test]
fn corrupt_z_file_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.test.3.Z");
    std::fs::write(&path, [0x1f, 0x9d, 0x90, 0x41, 0xff, 0xff, 0xff]).unwrap();
    let err = segcomp::read_range_image(&path).unwrap_err().to_string();
    assert!(
        err.contains("Unix compress (.Z) data") && err.contains("uncompress"),
        "{err}"
    );
}
