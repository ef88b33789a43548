//! A pole landmark, and its row of a pole-map CSV ([`raypath_io::poles_csv`]).

use raypath_io::poles_csv::PoleRecord;
use serde::{Deserialize, Serialize};

/// A pole: centre in the ground plane, vertical extent, footprint width and score (Schaefer
/// 2020, §12.4.1; the row `[x, y, z_start, z_end, width, score]` of `poles.py`). Metres in the
/// frame of the map it was extracted in.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pole {
    /// Centre x, metres.
    pub x: f64,
    /// Centre y, metres.
    pub y: f64,
    /// Bottom of the pole's voxel stack, metres.
    pub z_start: f64,
    /// Top of the pole's voxel stack, metres.
    pub z_end: f64,
    /// Footprint edge length, metres (score-weighted mean over the widths scored).
    pub width: f64,
    /// Mean remapped pole score in `[0, 1]`.
    pub score: f64,
}

impl Pole {
    /// Height of the voxel stack, metres.
    pub fn height(&self) -> f64 {
        self.z_end - self.z_start
    }

    /// True when the axis-aligned squares (centre, width) of the two poles overlap (closed
    /// intervals on both axes; Schaefer 2020, §12.4.2, and `cluster.py`).
    pub fn overlaps(&self, other: &Pole) -> bool {
        let reach = 0.5 * (self.width + other.width);
        (self.x - other.x).abs() <= reach && (self.y - other.y).abs() <= reach
    }
}

impl From<&Pole> for PoleRecord {
    /// The CSV row of a pole (`x,y,width,height,score`).
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

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use raypath_io::poles_csv::{parse_pole_csv, read_pole_csv, write_pole_csv, write_pole_csv_to};

    use super::*;

    fn records(poles: &[Pole]) -> Vec<PoleRecord> {
        poles.iter().map(PoleRecord::from).collect()
    }

    fn poles(records: Vec<PoleRecord>) -> Vec<Pole> {
        records.into_iter().map(Pole::from).collect()
    }

    #[test]
    fn csv_round_trip_and_foreign_headers() {
        let map = vec![Pole {
            x: 1.5,
            y: -2.25,
            z_start: 0.0,
            z_end: 3.0,
            width: 0.2,
            score: 0.8,
        }];
        let mut bytes = Vec::new();
        write_pole_csv_to(&mut bytes, &records(&map)).expect("write");
        let back = poles(parse_pole_csv(Cursor::new(bytes), "mem.csv").expect("read"));
        assert_eq!(back, map);
        let sim = Cursor::new(b"x,y,w,h,kind,id\n1,2,0.3,4,1,0\n".to_vec());
        let back = poles(parse_pole_csv(sim, "sim.csv").expect("read"));
        assert_eq!((back[0].width, back[0].height()), (0.3, 4.0));
    }

    #[test]
    fn file_round_trip() {
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("map.csv");
        let map = vec![Pole {
            x: -3.0,
            y: 4.5,
            z_start: 0.0,
            z_end: 2.5,
            width: 0.15,
            score: 0.25,
        }];
        write_pole_csv(&path, &records(&map)).expect("write");
        assert_eq!(poles(read_pole_csv(&path).expect("read")), map);
    }
}
