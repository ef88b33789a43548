//! Markdown tables for evaluation reports.

use anyhow::{Result, bail};

/// A markdown table built row by row.
#[derive(Clone, Debug, Default)]
pub struct Table {
    headers: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headers.
    pub fn new<S: ToString>(headers: impl IntoIterator<Item = S>) -> Self {
        Self {
            headers: headers.into_iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row. Its cell count must equal the header's: a row of another length is
    /// refused by [`Table::to_markdown`], so a cell is never silently dropped or shifted.
    pub fn row<S: ToString>(&mut self, cells: impl IntoIterator<Item = S>) -> &mut Self {
        self.rows
            .push(cells.into_iter().map(|c| c.to_string()).collect());
        self
    }

    /// The table as GitHub-flavoured markdown with aligned columns; an error naming the
    /// table and the row when a row's cell count differs from the header's.
    pub fn to_markdown(&self) -> Result<String> {
        if let Some((i, row)) = self
            .rows
            .iter()
            .enumerate()
            .find(|(_, r)| r.len() != self.headers.len())
        {
            bail!(
                "table [{}]: row {} has {} cells under {} headers: [{}]",
                self.headers.join(" | "),
                i + 1,
                row.len(),
                self.headers.len(),
                row.join(" | ")
            );
        }
        let widths: Vec<usize> = (0..self.headers.len())
            .map(|c| {
                self.rows
                    .iter()
                    .map(|r| r[c].chars().count())
                    .chain([self.headers[c].chars().count(), 3])
                    .max()
                    .unwrap_or(3)
            })
            .collect();
        let line = |cells: &[String]| {
            let padded: Vec<String> = cells
                .iter()
                .zip(&widths)
                .map(|(c, &w)| format!("{c:<w$}"))
                .collect();
            format!("| {} |\n", padded.join(" | "))
        };
        let mut out = line(&self.headers);
        let rule: Vec<String> = widths.iter().map(|&w| "-".repeat(w)).collect();
        out.push_str(&line(&rule));
        for row in &self.rows {
            out.push_str(&line(row));
        }
        Ok(out)
    }
}

/// Formats a number with `digits` significant decimals, or "—" when not finite.
pub fn fmt_num(value: f64, decimals: usize) -> String {
    if value.is_finite() {
        format!("{value:.decimals$}")
    } else {
        "—".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_aligned_markdown() {
        let mut table = Table::new(["a", "long header"]);
        table.row(["1", "2"]).row(["333", "4"]);
        assert_eq!(
            table.to_markdown().unwrap(),
            "| a   | long header |\n| --- | ----------- |\n| 1   | 2           |\n| 333 | 4           |\n"
        );
    }

    #[test]
    fn refuses_rows_of_the_wrong_length() {
        let mut long = Table::new(["a", "b"]);
        long.row(["1", "2"]).row(["1", "2", "3"]);
        let message = long.to_markdown().unwrap_err().to_string();
        assert!(
            message.contains("row 2 has 3 cells under 2 headers"),
            "{message}"
        );
        let mut short = Table::new(["a", "b"]);
        short.row(["1"]);
        assert!(short.to_markdown().is_err());
    }

    #[test]
    fn formats_non_finite_numbers_as_a_dash() {
        assert_eq!(fmt_num(1.23456, 2), "1.23");
        assert_eq!(fmt_num(f64::NAN, 2), "—");
        assert_eq!(fmt_num(f64::INFINITY, 0), "—");
    }
}
