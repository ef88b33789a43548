//! SegComp readers and the `.Z` decoder never panic on truncated or mutated input.
#![allow(clippy::unwrap_used)]

use proptest::prelude::*;
use raypath_io::lzw;
use raypath_io::segcomp::{parse_gt_ang, parse_gt_seg, parse_range_image};

fn range_file() -> Vec<u8> {
    let mut bytes = b"3 rows\n2 columns\n".to_vec();
    bytes.extend(b"header line\n".repeat(8));
    bytes.extend(b"\n");
    for i in 0..6u32 {
        bytes.extend((0x5000_0000 | (i * 500)).to_be_bytes());
    }
    bytes
}

fn seg_files() -> Vec<Vec<u8>> {
    let mut sun = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 12, 2, 1, 3] {
        sun.extend(w.to_be_bytes());
    }
    sun.extend([1, 2, 3]);
    sun.extend([0x80, 2, 10, 0, 0x80, 0, 11, 12, 0]);
    let mut plain = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 8, 1, 0, 0] {
        plain.extend(w.to_be_bytes());
    }
    plain.extend([10, 10, 11, 0, 12, 12, 13, 0]);
    let mut pgm = b"P5\n# c\n3 2\n300\n".to_vec();
    pgm.extend([0, 10, 0, 11, 1, 44, 0, 12, 0, 13, 0, 14]);
    let mut raw = b"2 rows\n3 columns\n".to_vec();
    raw.extend(b"x\n".repeat(9));
    raw.extend([10, 11, 12, 13, 14, 15]);
    vec![sun, plain, pgm, b"P2 2 2 20\n1 2\n3 20\n".to_vec(), raw]
}

fn mutate(mut bytes: Vec<u8>, cut: f64, edits: &[(f64, u8)]) -> Vec<u8> {
    if cut < 0.5 {
        let keep = (cut * 2.0 * bytes.len() as f64) as usize;
        bytes.truncate(keep);
    }
    for &(at, v) in edits {
        if !bytes.is_empty() {
            let i = ((at * bytes.len() as f64) as usize).min(bytes.len() - 1);
            bytes[i] = v;
        }
    }
    bytes
}

fn edits() -> impl Strategy<Value = Vec<(f64, u8)>> {
    prop::collection::vec((0.0f64..1.0, any::<u8>()), 0..5)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn range_never_panics(cut in 0.0f64..1.0, edits in edits()) {
        let bytes = mutate(range_file(), cut, &edits);
        if let Ok(image) = parse_range_image(&bytes, "m") {
            prop_assert_eq!(image.range.len(), image.rows * image.columns);
            prop_assert!(image.range.iter().all(|&r| r < 4096));
        }
    }

    #[test]
    fn gt_seg_never_panics(which in 0usize..5, cut in 0.0f64..1.0, edits in edits()) {
        let bytes = mutate(seg_files()[which].clone(), cut, &edits);
        if let Ok(seg) = parse_gt_seg(&bytes, "m") {
            prop_assert_eq!(seg.labels.len(), seg.rows * seg.columns);
        }
    }

    #[test]
    fn gt_ang_never_panics(cut in 0.0f64..1.0, edits in edits()) {
        let bytes = mutate(b"3\n10 11 90\n11 12 45\n\n10 12 135\n".to_vec(), cut, &edits);
        if let Ok(angles) = parse_gt_ang(std::io::Cursor::new(bytes), "m") {
            prop_assert!(angles.pairs.iter().all(|p| (0.0..=180.0).contains(&p.angle_deg)));
        }
    }

    #[test]
    fn lzw_never_panics(which in 0usize..3, cut in 0.0f64..1.0, edits in edits()) {
        let name = ["tobe", "mixed-b12", "text-b16"][which];
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/lzw/{name}.Z"));
        let bytes = mutate(std::fs::read(path).unwrap(), cut, &edits);
        let _ = lzw::decompress(&bytes, 1 << 20);
    }
}
