//! SegComp ground-truth angles (`<name>.gt-ang`): the angle between adjacent planes.
//!
//! ASCII: the first line holds the number N of entries, then N lines `label_i label_j
//! angle_deg` (integer degrees in the original files) for pairs of adjacent ground-truth
//! regions. Blank lines are ignored.

use std::collections::BTreeSet;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use super::load;
use crate::Result;
use crate::source::{LineReader, parse_field};

/// Most entries accepted (a scan has a few dozen).
const MAX_PAIRS: usize = 1 << 20;

/// The ground-truth angle between two adjacent regions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnglePair {
    /// First region label.
    pub label_a: u32,
    /// Second region label.
    pub label_b: u32,
    /// Angle between the two planes, degrees (0–180).
    pub angle_deg: f64,
}

/// The contents of a `.gt-ang` file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroundTruthAngles {
    /// The pairs in file order.
    pub pairs: Vec<AnglePair>,
}

impl GroundTruthAngles {
    /// Distinct labels that appear in any pair, ascending.
    pub fn labels(&self) -> Vec<u32> {
        self.pairs
            .iter()
            .flat_map(|p| [p.label_a, p.label_b])
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect()
    }
}

/// Reads a `.gt-ang` file (plain, `.Z`, gzip or bzip2).
pub fn read_gt_ang(path: &Path) -> Result<GroundTruthAngles> {
    parse_gt_ang(std::io::Cursor::new(load(path)?), path)
}

/// Parses `.gt-ang` text from `reader`; `name` names it in errors.
pub fn parse_gt_ang(
    reader: impl BufRead + Send + 'static,
    name: impl Into<PathBuf>,
) -> Result<GroundTruthAngles> {
    let mut lines = LineReader::new(reader, name);
    let count = loop {
        let Some(line) = lines.next_line()? else {
            return Err(crate::Error::truncated(
                lines.path(),
                crate::Location::Line(1),
                "the number of entries",
            ));
        };
        let line = line.trim().to_owned();
        if line.is_empty() {
            continue;
        }
        let n: usize = parse_field(&lines, Some(&line), "number of entries")?;
        if n > MAX_PAIRS {
            return Err(lines.error(format!("{n} entries exceed the limit of {MAX_PAIRS}")));
        }
        break n;
    };
    let mut pairs = Vec::with_capacity(count.min(1024));
    while let Some(line) = lines.next_line()? {
        let line = line.to_owned(); // a few dozen short lines
        let mut fields = line.split_whitespace();
        let Some(first) = fields.next() else {
            continue;
        };
        if pairs.len() == count {
            return Err(lines.error(format!("more entries than the {count} announced")));
        }
        let label_a = parse_field(&lines, Some(first), "first label")?;
        let label_b = parse_field(&lines, fields.next(), "second label")?;
        let angle_deg: f64 = parse_field(&lines, fields.next(), "angle")?;
        if !(0.0..=180.0).contains(&angle_deg) {
            return Err(lines.error(format!(
                "angle {angle_deg} is not between 0 and 180 degrees"
            )));
        }
        if fields.next().is_some() {
            return Err(lines.error("more than three values on the line"));
        }
        pairs.push(AnglePair {
            label_a,
            label_b,
            angle_deg,
        });
    }
    if pairs.len() < count {
        return Err(crate::Error::truncated(
            lines.path(),
            crate::Location::Line(lines.line_number() + 1),
            format!("entry {} of {count}", pairs.len() + 1),
        ));
    }
    Ok(GroundTruthAngles { pairs })
}
