//! Pole maps as CSV (`x,y,width,height,score`, metres; header line first) and JSON (an array
//! of [`Pole`] objects). The CSV reader takes columns by header name, so it also reads the
//! ground-truth pole lists of `raypath-sim` (`x,y,w,h,kind,id`) and of `RAYPATH_DATA`
//! (`x,y`, `x,y,z`, `x,y,w`): `x` and `y` are required, `width`/`w`, `height`/`h`, `score`
//! optional (0 when absent).

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use crate::error::{PoleError, Result};
use crate::pole::Pole;

/// The CSV header written.
pub const POLE_MAP_HEADER: &str = "x,y,width,height,score";

/// Writes poles as CSV.
pub fn write_pole_csv(path: &Path, poles: &[Pole]) -> Result<()> {
    let io = |source| PoleError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut out = std::io::BufWriter::new(file);
    write_pole_csv_to(&mut out, poles).map_err(io)?;
    out.flush().map_err(io)
}

/// Writes poles as CSV to a writer.
pub fn write_pole_csv_to(mut out: impl Write, poles: &[Pole]) -> std::io::Result<()> {
    writeln!(out, "{POLE_MAP_HEADER}")?;
    for p in poles {
        writeln!(
            out,
            "{:.4},{:.4},{:.4},{:.4},{:.4}",
            p.x,
            p.y,
            p.width,
            p.height(),
            p.score
        )?;
    }
    Ok(())
}

/// Reads a pole CSV file.
pub fn read_pole_csv(path: &Path) -> Result<Vec<Pole>> {
    let file = std::fs::File::open(path).map_err(|source| PoleError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_pole_csv(BufReader::new(file), path)
}

/// Parses a pole CSV from a reader; `name` is used in errors.
pub fn parse_pole_csv(reader: impl BufRead, name: impl Into<PathBuf>) -> Result<Vec<Pole>> {
    let name = name.into();
    let malformed = |line: u64, reason: String| PoleError::Malformed {
        path: name.clone(),
        line,
        reason,
    };
    let mut lines = reader.lines();
    let header = match lines.next() {
        Some(Ok(h)) => h,
        Some(Err(source)) => {
            return Err(PoleError::Io {
                path: name.clone(),
                source,
            });
        }
        None => return Err(malformed(1, "empty file: expected a header line".into())),
    };
    let columns: Vec<String> = header
        .trim()
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    let find = |names: &[&str]| columns.iter().position(|c| names.contains(&c.as_str()));
    let (Some(ix), Some(iy)) = (find(&["x"]), find(&["y"])) else {
        return Err(malformed(
            1,
            format!("header {header:?} lacks the columns x and y"),
        ));
    };
    let iw = find(&["width", "w"]);
    let ih = find(&["height", "h"]);
    let is = find(&["score"]);
    let mut poles = Vec::new();
    for (k, line) in lines.enumerate() {
        let number = k as u64 + 2;
        let line = line.map_err(|source| PoleError::Io {
            path: name.clone(),
            source,
        })?;
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != columns.len() {
            return Err(malformed(
                number,
                format!("{} fields, the header has {}", fields.len(), columns.len()),
            ));
        }
        let value = |i: Option<usize>, what: &str| -> Result<f64> {
            let Some(i) = i else { return Ok(0.0) };
            let text = fields.get(i).copied().unwrap_or("");
            let v: f64 = text
                .parse()
                .map_err(|_| malformed(number, format!("{what} {text:?} is not a number")))?;
            if !v.is_finite() {
                return Err(malformed(number, format!("{what} {text:?} is not finite")));
            }
            Ok(v)
        };
        let height = value(ih, "height")?;
        poles.push(Pole {
            x: value(Some(ix), "x")?,
            y: value(Some(iy), "y")?,
            z_start: 0.0,
            z_end: height,
            width: value(iw, "width")?,
            score: value(is, "score")?,
        });
    }
    Ok(poles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_and_foreign_headers() {
        let poles = vec![Pole {
            x: 1.5,
            y: -2.25,
            z_start: 0.0,
            z_end: 3.0,
            width: 0.2,
            score: 0.8,
        }];
        let mut bytes = Vec::new();
        write_pole_csv_to(&mut bytes, &poles).expect("write");
        let back = parse_pole_csv(bytes.as_slice(), "mem.csv").expect("read");
        assert_eq!(back, poles);
        let sim = "x,y,w,h,kind,id\n1,2,0.3,4,1,0\n";
        let back = parse_pole_csv(sim.as_bytes(), "sim.csv").expect("read");
        assert_eq!((back[0].width, back[0].height()), (0.3, 4.0));
        let bad = parse_pole_csv("x,y\n1,nan\n".as_bytes(), "bad.csv");
        assert!(matches!(bad, Err(PoleError::Malformed { line: 2, .. })));
        assert!(parse_pole_csv("a,b\n".as_bytes(), "h.csv").is_err());
        assert!(parse_pole_csv("".as_bytes(), "e.csv").is_err());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(1000))]
        #[test]
        fn mutated_csv_never_panics(cut in 0usize..80, pos in 0usize..80, byte in 0u8..=255) {
            let mut text = b"x,y,width,height,score\n1.0,2.0,0.2,3.0,0.7\n-4,5e1,0.1,2,0.6\n".to_vec();
            if let Some(b) = text.get_mut(pos) { *b = byte; }
            text.truncate(cut.max(1));
            let _ = parse_pole_csv(text.as_slice(), "fuzz.csv");
        }
    }
}
