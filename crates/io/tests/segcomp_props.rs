//! SegComp readers and the `.Z` decoder never panic on truncated or mutated input.
#![allow(clippy::unwrap_used)]

use proptest::prelude::*;
use raypath_io::segcomp::{parse_gt_ang, parse_gt_seg, parse_range_image};
use raypath_io::{lzw, samples};

/// The hand-made range image of `raypath_io::samples`.
fn range_file() -> Vec<u8> {
    samples::segcomp_range().unwrap().remove(0).bytes
}

/// The five hand-made ground-truth rasters of `raypath_io::samples`.
fn seg_files() -> Vec<Vec<u8>> {
    let files: Vec<_> = samples::segcomp_gt_seg()
        .unwrap()
        .into_iter()
        .map(|s| s.bytes)
        .collect();
    files[..5].to_vec()
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
