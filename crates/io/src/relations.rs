//! Relation files of the SLAM benchmark (Kümmerle et al. 2009, "On measuring the accuracy of
//! SLAM algorithms"; the `*.relations` files of the Freiburg SLAM evaluation site): one
//! relation per line,
//!
//! ```text
//! # timestamp1 timestamp2 x y z roll pitch yaw
//! 1232658478.161285 1232658644.149293 1.031273 -0.003531 0.000000 0.000000 -0.000000 -0.009755
//! ```
//!
//! the pose of the scan taken at `timestamp2` in the frame of the scan taken at `timestamp1`
//! (`x₁⁻¹ ⊕ x₂`; metres, radians). The time stamps are the CARMEN logs' **ipc** time stamps
//! ([`PlanarFrame::ipc_stamp_secs`](crate::sequence::PlanarFrame::ipc_stamp_secs)), which is
//! how the benchmark names scans. A planar relation has `z`, `roll` and `pitch` zero; the
//! reader requires them to be finite and keeps `x`, `y` and `yaw`.

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use raypath_geometry::Pose2;

use crate::source::{LineReader, finite_fields};
use crate::{Error, Location, Result};

/// One relation: the reference pose of scan `b` in the frame of scan `a`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relation {
    /// Time stamp of the first scan, seconds.
    pub stamp_a_secs: f64,
    /// Time stamp of the second scan, seconds.
    pub stamp_b_secs: f64,
    /// `a_from_b = x_a⁻¹ ⊕ x_b`.
    pub a_from_b: Pose2,
}

/// Reads a relation file (plain or compressed).
pub fn read_relations(path: &Path) -> Result<Vec<Relation>> {
    relations_from(LineReader::open(path)?)
}

/// Parses a relation file from `reader`; `name` is used in errors.
pub fn parse_relations(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<Relation>> {
    relations_from(LineReader::new(reader, name))
}

const FIELDS: [&str; 8] = [
    "timestamp1",
    "timestamp2",
    "x",
    "y",
    "z",
    "roll",
    "pitch",
    "yaw",
];

fn relations_from(mut lines: LineReader) -> Result<Vec<Relation>> {
    let mut relations = Vec::new();
    while let Some(line) = lines.next_line()?.map(|l| l.trim().to_owned()) {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let [a, b, x, y, _z, _roll, _pitch, yaw] = finite_fields(
            &lines,
            &line,
            FIELDS,
            "timestamp1 timestamp2 x y z roll pitch yaw",
        )?;
        relations.push(Relation {
            stamp_a_secs: a,
            stamp_b_secs: b,
            a_from_b: Pose2::new(x, y, yaw),
        });
    }
    Ok(relations)
}

/// Writes relations in the benchmark's format (time stamps with six decimals as the benchmark
/// writes them, poses with nine): a reference trajectory turned into relations can be scored
/// by the benchmark's own tools, and ours read the benchmark's files.
pub fn write_relations(path: &Path, relations: &[Relation]) -> Result<()> {
    if let Some(k) = relations.iter().position(|r| {
        !(r.stamp_a_secs.is_finite() && r.stamp_b_secs.is_finite() && r.a_from_b.is_finite())
    }) {
        return Err(Error::Unwritable {
            path: path.into(),
            reason: format!("relation {k} has a non-finite time stamp or pose"),
        });
    }
    let io = |source| Error::io(path, Location::File, source);
    let file = std::fs::File::create(path).map_err(io)?;
    let mut out = std::io::BufWriter::new(file);
    write_relations_to(&mut out, relations).map_err(io)?;
    out.flush().map_err(io)
}

/// Writes relations to a writer (see [`write_relations`]).
pub fn write_relations_to(mut out: impl Write, relations: &[Relation]) -> std::io::Result<()> {
    writeln!(out, "# timestamp1 timestamp2 x y z roll pitch yaw")?;
    for r in relations {
        let p = &r.a_from_b;
        writeln!(
            out,
            "{:.6} {:.6} {:.9} {:.9} 0.000000 0.000000 0.000000 {:.9}",
            r.stamp_a_secs,
            r.stamp_b_secs,
            p.x(),
            p.y(),
            p.theta()
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<Relation>> {
        parse_relations(std::io::Cursor::new(text.to_owned()), "test.relations")
    }

    /// The two lines the benchmark's documentation shows.
    #[test]
    fn reads_the_documented_example() {
        let r = parse(
            "# timestamp1 timestamp2 x y z roll pitch yaw\n\
             1232658478.161285 1232658644.149293 1.031273 -0.003531 0.000000 0.000000 -0.000000 -0.009755\n\
             \n\
             1232658478.161285 1232658647.058497 2.039538 -0.014451 0.000000 0.000000 -0.000000 -0.016492\n",
        )
        .expect("valid file");
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].stamp_a_secs, 1232658478.161285);
        assert_eq!(r[1].stamp_b_secs, 1232658647.058497);
        assert_eq!(r[1].a_from_b.x(), 2.039538);
        assert!((r[1].a_from_b.theta() + 0.016492).abs() < 1e-15);
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        for (text, line) in [
            ("1 2 3\n", 1),
            ("# c\n1 2 3 4 5 6 7 8 9\n", 2),
            ("1 2 nan 0 0 0 0 0\n", 1),
            ("1 2 0 0 0 0 0 x\n", 1),
            ("1 2 0 0 0 0 0 0\n1 2 0 0 inf 0 0 0\n", 2),
        ] {
            let e = parse(text).expect_err(text).to_string();
            assert!(e.starts_with(&format!("test.relations:{line}:")), "{e}");
        }
    }

    #[test]
    fn written_relations_read_back() {
        let relations = vec![
            Relation {
                stamp_a_secs: 976052857.33753,
                stamp_b_secs: 976052858.5,
                a_from_b: Pose2::new(0.25, -0.125, 0.5),
            },
            Relation {
                stamp_a_secs: 1.0,
                stamp_b_secs: 2.0,
                a_from_b: Pose2::new(-3.0, 4.0, -3.0),
            },
        ];
        let mut bytes = Vec::new();
        write_relations_to(&mut bytes, &relations).expect("in memory");
        let back = parse_relations(std::io::Cursor::new(bytes), "x").expect("own output");
        assert_eq!(back.len(), 2);
        for (a, b) in relations.iter().zip(&back) {
            assert!((a.stamp_a_secs - b.stamp_a_secs).abs() < 1e-6);
            assert!((a.stamp_b_secs - b.stamp_b_secs).abs() < 1e-6);
            let d = a.a_from_b.inverse() * b.a_from_b;
            assert!(d.translation().norm() < 1e-8 && d.theta().abs() < 1e-8);
        }
        let dir = tempfile::tempdir().expect("temp dir");
        let bad = [Relation {
            stamp_a_secs: f64::NAN,
            ..relations[0]
        }];
        let e = write_relations(&dir.path().join("bad.relations"), &bad).expect_err("NaN");
        assert!(e.to_string().contains("relation 0"), "{e}");
    }
}
