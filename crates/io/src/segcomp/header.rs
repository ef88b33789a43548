//! The text header of SegComp Perceptron files: 10 lines (line 1 holds the number of rows,
//! line 2 the number of columns) and one more line before the binary data.

use std::path::Path;

use crate::{Error, Location, Result};

/// Largest image side accepted (the SegComp images are 512 × 512).
pub(crate) const MAX_SIDE: usize = 8192;
const HEADER_LINES: usize = 10;
/// Longest header line accepted.
const MAX_LINE: usize = 1024;

/// A parsed Perceptron text header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct TextHeader {
    /// The header lines (10, or 11 with the extra line), without line endings.
    pub lines: Vec<String>,
    /// Image rows (line 1).
    pub rows: usize,
    /// Image columns (line 2).
    pub columns: usize,
    /// Where the data starts if the extra "line" is a single byte after line 10 (what the
    /// original C reader assumes), and if it is a full line.
    pub data_starts: [usize; 2],
}

/// Splits off the header of `bytes`. Errors name the line.
pub(crate) fn parse(bytes: &[u8], path: &Path) -> Result<TextHeader> {
    let mut lines = Vec::with_capacity(HEADER_LINES + 1);
    let mut start = 0usize;
    for number in 1..=HEADER_LINES {
        let at = Location::Line(number as u64);
        let rest = bytes.get(start..).unwrap_or_default();
        match text_line(rest) {
            Some(Ok((line, used))) => {
                lines.push(line);
                start += used;
            }
            Some(Err(reason)) => return Err(Error::malformed(path, at, reason)),
            None => return Err(Error::truncated(path, at, "the 11-line SegComp header")),
        }
    }
    let after_ten = start;
    // The extra line: a full text line, or (as the original C reader assumes) one byte.
    let mut after_extra = after_ten + 1;
    if let Some(Ok((line, used))) = text_line(bytes.get(after_ten..).unwrap_or_default()) {
        lines.push(line);
        after_extra = after_ten + used;
    }
    let rows = side(&lines, 0, "rows", path)?;
    let columns = side(&lines, 1, "columns", path)?;
    Ok(TextHeader {
        lines,
        rows,
        columns,
        data_starts: [after_ten + 1, after_extra],
    })
}

/// The text line at the start of `rest` and the bytes it takes with its `\n`; `None` when no
/// line end follows, `Err` when it is not a text line.
fn text_line(rest: &[u8]) -> Option<std::result::Result<(String, usize), String>> {
    let Some(end) = rest.iter().take(MAX_LINE + 1).position(|&b| b == b'\n') else {
        return (rest.len() > MAX_LINE)
            .then(|| Err("header line longer than 1024 bytes (not a SegComp header?)".into()));
    };
    let line = rest.get(..end).unwrap_or_default();
    Some(
        std::str::from_utf8(line)
            .ok()
            .filter(|t| !t.contains('\0'))
            .map(|t| (t.trim_end_matches('\r').to_owned(), end + 1))
            .ok_or_else(|| "header line is not text (not a SegComp header?)".into()),
    )
}

/// The first integer on header line `index + 1`.
fn side(lines: &[String], index: usize, what: &str, path: &Path) -> Result<usize> {
    let at = Location::Line(index as u64 + 1);
    let line = lines.get(index).map(String::as_str).unwrap_or_default();
    let value = line
        .split(|c: char| c.is_whitespace() || c == ':' || c == '=' || c == ',')
        .find_map(|t| t.parse::<usize>().ok())
        .ok_or_else(|| Error::malformed(path, at, format!("no number of {what} in {line:?}")))?;
    if !(1..=MAX_SIDE).contains(&value) {
        return Err(Error::malformed(
            path,
            at,
            format!("{value} {what} is not between 1 and {MAX_SIDE}"),
        ));
    }
    Ok(value)
}

impl TextHeader {
    /// Where data of `bytes_per_pixel` bytes per pixel starts so that it fills the rest of a
    /// `total`-byte file exactly, or an error naming the mismatch.
    pub fn data_start(
        &self,
        total: usize,
        bytes_per_pixel: &[usize],
        path: &Path,
    ) -> Result<(usize, usize)> {
        let pixels = self.rows * self.columns;
        for &bpp in bytes_per_pixel {
            for start in self.data_starts {
                if total.checked_sub(start) == Some(pixels * bpp) {
                    return Ok((start, bpp));
                }
            }
        }
        let start = self.data_starts[1];
        let present = total.saturating_sub(start);
        let wanted = pixels * bytes_per_pixel.first().copied().unwrap_or(1);
        Err(if present < wanted {
            // A file that ends with line 10 has no extra line: its end is where data is missing.
            Error::truncated(
                path,
                Location::Byte(start.min(total) as u64),
                format!(
                    "{} × {} pixels ({wanted} bytes, {present} present)",
                    self.rows, self.columns
                ),
            )
        } else {
            Error::malformed(
                path,
                Location::Byte((start + wanted) as u64),
                format!(
                    "{} bytes after the {} × {} pixels",
                    present - wanted,
                    self.rows,
                    self.columns
                ),
            )
        })
    }
}
