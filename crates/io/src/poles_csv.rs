//! Pole maps as CSV: `x,y,width,height,score` (metres; the score in `[0, 1]`), a header line
//! first.
//!
//! The reader takes the columns by header name (case-insensitive) on top of
//! [`crate::point_csv`], so it also reads the ground-truth pole lists of `raypath-sim`
//! (`x,y,w,h,kind,id`) and of the pole-localization data sets (`x,y`, `x,y,z`, `x,y,w`):
//! `x` and `y` (the first two columns) are required; `width` or `w`, `height` or `h`, and
//! `score` are optional (0 when absent); other columns are ignored. Errors name the file and
//! the line.
//!
//! ```
//! use raypath_io::poles_csv::{PoleRecord, parse_pole_csv, write_pole_csv_to};
//! let poles = vec![PoleRecord { x: 1.5, y: -2.25, width: 0.2, height: 3.0, score: 0.8 }];
//! let mut bytes = Vec::new();
//! write_pole_csv_to(&mut bytes, &poles)?;
//! assert_eq!(parse_pole_csv(std::io::Cursor::new(bytes), "map.csv")?, poles);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use crate::point_csv::PointCsvReader;
use crate::{Error, Location, Result};

/// The CSV header written.
pub const POLE_MAP_HEADER: &str = "x,y,width,height,score";

/// One pole of a map: a vertical cylinder standing on the ground.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoleRecord {
    /// Position of the axis, metres (map frame).
    pub x: f64,
    /// Position of the axis, metres (map frame).
    pub y: f64,
    /// Width (footprint edge or diameter), metres (0 when the file does not state it).
    pub width: f64,
    /// Height above the ground, metres (0 when the file does not state it).
    pub height: f64,
    /// Detection score (0 when the file does not state it).
    pub score: f64,
}

/// Reads a pole CSV file (plain or compressed).
pub fn read_pole_csv(path: &Path) -> Result<Vec<PoleRecord>> {
    poles_from(PointCsvReader::open(path)?)
}

/// Parses a pole CSV from `reader`; `name` is used in errors.
pub fn parse_pole_csv(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<PoleRecord>> {
    poles_from(PointCsvReader::new(reader, name)?)
}

fn poles_from(mut csv: PointCsvReader) -> Result<Vec<PoleRecord>> {
    let find = |names: &[&str]| {
        csv.columns()
            .iter()
            .position(|c| names.iter().any(|n| c.eq_ignore_ascii_case(n)))
    };
    let (width, height, score) = (
        find(&["width", "w"]),
        find(&["height", "h"]),
        find(&["score"]),
    );
    let mut poles = Vec::new();
    while let Some(row) = csv.next_row()? {
        let get = |i: Option<usize>| i.and_then(|i| row.get(i)).copied().unwrap_or(0.0);
        poles.push(PoleRecord {
            x: get(Some(0)),
            y: get(Some(1)),
            width: get(width),
            height: get(height),
            score: get(score),
        });
    }
    Ok(poles)
}

/// Writes poles as CSV ([`POLE_MAP_HEADER`], four decimals).
pub fn write_pole_csv(path: &Path, poles: &[PoleRecord]) -> Result<()> {
    let io = |source| Error::io(path, Location::File, source);
    let file = std::fs::File::create(path).map_err(io)?;
    let mut out = std::io::BufWriter::new(file);
    write_pole_csv_to(&mut out, poles).map_err(io)?;
    out.flush().map_err(io)
}

/// Writes poles as CSV to a writer.
pub fn write_pole_csv_to(mut out: impl Write, poles: &[PoleRecord]) -> std::io::Result<()> {
    writeln!(out, "{POLE_MAP_HEADER}")?;
    for p in poles {
        writeln!(
            out,
            "{:.4},{:.4},{:.4},{:.4},{:.4}",
            p.x, p.y, p.width, p.height, p.score
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::*;

    fn parse(text: &str, name: &str) -> Result<Vec<PoleRecord>> {
        parse_pole_csv(Cursor::new(text.as_bytes().to_vec()), name)
    }

    #[test]
    fn round_trip_and_foreign_headers() {
        let poles = vec![
            PoleRecord {
                x: 1.5,
                y: -2.25,
                width: 0.2,
                height: 3.0,
                score: 0.8,
            },
            PoleRecord {
                x: -1e3,
                y: 0.0,
                width: 0.05,
                height: 0.0,
                score: 1.0,
            },
        ];
        let mut bytes = Vec::new();
        write_pole_csv_to(&mut bytes, &poles).unwrap();
        assert!(bytes.starts_with(b"x,y,width,height,score\n1.5000,-2.2500,"));
        assert_eq!(
            parse_pole_csv(Cursor::new(bytes), "mem.csv").unwrap(),
            poles
        );
        // raypath-sim's ground truth: w and h by their short names, other columns ignored.
        let sim = parse("x,y,w,h,kind,id\n1,2,0.3,4,1,0\n\n", "sim.csv").unwrap();
        assert_eq!(
            sim,
            [PoleRecord {
                x: 1.0,
                y: 2.0,
                width: 0.3,
                height: 4.0,
                score: 0.0
            }]
        );
        // The NCLT ground truth: x,y,z (z is not a height).
        let nclt = parse("X,Y,Z\n3,4,5\n", "gt.csv").unwrap();
        assert_eq!((nclt[0].x, nclt[0].y, nclt[0].height), (3.0, 4.0, 0.0));
    }

    #[test]
    fn file_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.csv");
        let poles = [PoleRecord {
            x: 7.0,
            y: 8.0,
            width: 0.1,
            height: 2.0,
            score: 0.5,
        }];
        write_pole_csv(&path, &poles).unwrap();
        assert_eq!(read_pole_csv(&path).unwrap(), poles);
        let missing = read_pole_csv(&dir.path().join("none.csv")).unwrap_err();
        assert!(missing.to_string().contains("none.csv"), "{missing}");
    }

    #[test]
    fn errors_name_file_and_line() {
        let nan = parse("x,y\n1,2\n1,nan\n", "bad.csv")
            .unwrap_err()
            .to_string();
        assert!(nan.starts_with("bad.csv:3:"), "{nan}");
        let fields = parse("x,y,w\n1,2\n", "f.csv").unwrap_err().to_string();
        assert!(fields.starts_with("f.csv:2:"), "{fields}");
        let header = parse("a,b\n1,2\n", "h.csv").unwrap_err().to_string();
        assert!(header.starts_with("h.csv:1:"), "{header}");
        let empty = parse("", "e.csv").unwrap_err().to_string();
        assert!(empty.starts_with("e.csv:1:"), "{empty}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(1000))]
        #[test]
        fn mutated_and_truncated_csv_never_panics(
            cut in 0usize..80,
            pos in 0usize..80,
            byte in 0u8..=255,
        ) {
            let mut text =
                b"x,y,width,height,score\n1.0,2.0,0.2,3.0,0.7\n-4,5e1,0.1,2,0.6\n".to_vec();
            if let Some(b) = text.get_mut(pos) {
                *b = byte;
            }
            text.truncate(cut.max(1));
            let _ = parse_pole_csv(Cursor::new(text), "fuzz.csv");
        }
    }
}
