//! Pole maps as CSV (`x,y,width,height,score`, metres; header line first; read and written
//! by [`raypath_io::poles_csv`]) and JSON (an array of [`Pole`] objects). The CSV reader takes
//! columns by header name, so it also reads the ground-truth pole lists of `raypath-sim`
//! (`x,y,w,h,kind,id`) and of `RAYPATH_DATA` (`x,y`, `x,y,z`, `x,y,w`): `x` and `y` are
//! required, `width`/`w`, `height`/`h`, `score` optional (0 when absent).

use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

use raypath_io::poles_csv::{self, PoleRecord};

use crate::error::Result;
use crate::pole::Pole;

/// The CSV header written.
pub use raypath_io::poles_csv::POLE_MAP_HEADER;

impl From<&Pole> for PoleRecord {
    fn from(p: &Pole) -> Self {
        PoleRecord {
            x: p.x,
            y: p.y,
            width: p.width,
            height: p.height(),
            score: p.score,
        }
    }
}

impl From<PoleRecord> for Pole {
    /// A pole standing on the ground (`z_start = 0`, `z_end` = the height).
    fn from(r: PoleRecord) -> Self {
        Pole {
            x: r.x,
            y: r.y,
            z_start: 0.0,
            z_end: r.height,
            width: r.width,
            score: r.score,
        }
    }
}

fn records(poles: &[Pole]) -> Vec<PoleRecord> {
    poles.iter().map(PoleRecord::from).collect()
}

/// Writes poles as CSV.
pub fn write_pole_csv(path: &Path, poles: &[Pole]) -> Result<()> {
    Ok(poles_csv::write_pole_csv(path, &records(poles))?)
}

/// Writes poles as CSV to a writer.
pub fn write_pole_csv_to(out: impl Write, poles: &[Pole]) -> std::io::Result<()> {
    poles_csv::write_pole_csv_to(out, &records(poles))
}

/// Reads a pole CSV file (plain or compressed).
pub fn read_pole_csv(path: &Path) -> Result<Vec<Pole>> {
    let records = poles_csv::read_pole_csv(path)?;
    Ok(records.into_iter().map(Pole::from).collect())
}

/// Parses a pole CSV from a reader; `name` is used in errors.
pub fn parse_pole_csv(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<Vec<Pole>> {
    let records = poles_csv::parse_pole_csv(reader, name)?;
    Ok(records.into_iter().map(Pole::from).collect())
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

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
        let back = parse_pole_csv(Cursor::new(bytes), "mem.csv").expect("read");
        assert_eq!(back, poles);
        let sim = Cursor::new(b"x,y,w,h,kind,id\n1,2,0.3,4,1,0\n".to_vec());
        let back = parse_pole_csv(sim, "sim.csv").expect("read");
        assert_eq!((back[0].width, back[0].height()), (0.3, 4.0));
        let bad = parse_pole_csv(Cursor::new(b"x,y\n1,nan\n".to_vec()), "bad.csv")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(bad.starts_with("bad.csv:2:"), "{bad}");
        assert!(parse_pole_csv(Cursor::new(b"a,b\n".to_vec()), "h.csv").is_err());
        assert!(parse_pole_csv(Cursor::new(Vec::new()), "e.csv").is_err());
    }

    #[test]
    fn file_round_trip() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("map.csv");
        let poles = vec![Pole {
            x: -3.0,
            y: 4.5,
            z_start: 0.0,
            z_end: 2.5,
            width: 0.15,
            score: 0.25,
        }];
        write_pole_csv(&path, &poles).expect("write");
        assert_eq!(read_pole_csv(&path).expect("read"), poles);
    }
}
