//! SLAM-benchmark relation files: mutated and truncated input never panics, every error names
//! its line, and every relation read is finite.

use std::io::Cursor;

mod common;

use proptest::prelude::*;
use raypath_io::Location;
use raypath_io::relations::parse_relations;

const SOURCE: &[u8] = b"# timestamp1 timestamp2 x y z roll pitch yaw\n\
1232658478.161285 1232658644.149293 1.031273 -0.003531 0.000000 0.000000 -0.000000 -0.009755\n\
1232658478.161285 1232658647.058497 2.039538 -0.014451 0.000000 0.000000 -0.000000 -0.016492\n\
976052857.337530 976052858.5 -1e-3 4 0 0 0 3.1\n";

const ALPHABET: &[u8] = b"0123456789.-+e\n #naif";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn reader_never_panics(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<usize>()), 0..5),
        invalid_utf8 in any::<bool>(),
    ) {
        let bytes = common::mutated(SOURCE, cut, &edits, invalid_utf8, ALPHABET);
        match parse_relations(Cursor::new(bytes), "r.relations") {
            Ok(relations) => {
                prop_assert!(relations.len() <= 3);
                for r in relations {
                    prop_assert!(r.stamp_a_secs.is_finite() && r.stamp_b_secs.is_finite());
                    prop_assert!(r.a_from_b.is_finite());
                }
            }
            Err(e) => {
                prop_assert!(matches!(e.location(), Location::Line(_)), "{}", e);
                prop_assert!(e.to_string().starts_with("r.relations:"), "{}", e);
            }
        }
    }
}
