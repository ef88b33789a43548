//! The "comparable" column (project rule): every table that sets our figures beside a thesis
//! or peer figure says, per row, whether the figures are like for like — "yes — why" or
//! "no — why" (data real or simulated, same protocol or not, same hardware or not). Our own
//! rows name their data (real, simulated, semi-synthetic) in the same cell.

/// The column header.
pub const HEADER: &str = "comparable";

/// "yes — `why`".
pub fn yes(why: &str) -> String {
    format!("yes — {why}")
}

/// "no — `why`".
pub fn no(why: &str) -> String {
    format!("no — {why}")
}

/// The last cell of a markdown table line, trimmed (tests: is it the "comparable" column?).
/// How our logs overlap a thesis' list: how many of ours it used, its logs we lack, and
/// ours it did not use.
pub fn log_overlap<'a>(
    ours: &[&'a str],
    thesis: &[&'a str],
) -> (usize, Vec<&'a str>, Vec<&'a str>) {
    let shared = ours.iter().filter(|l| thesis.contains(l)).count();
    let absent = thesis
        .iter()
        .filter(|t| !ours.contains(t))
        .copied()
        .collect();
    let extra = ours
        .iter()
        .filter(|l| !thesis.contains(l))
        .copied()
        .collect();
    (shared, absent, extra)
}

#[cfg(test)]
pub fn last_cell(line: &str) -> &str {
    line.trim_end()
        .trim_end_matches('|')
        .rsplit('|')
        .next()
        .unwrap_or("")
        .trim()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_lead_with_the_verdict() {
        assert_eq!(yes("same logs"), "yes — same logs");
        assert_eq!(no("simulated"), "no — simulated");
        assert_eq!(HEADER, "comparable");
        assert_eq!(last_cell("| a | comparable    |"), "comparable");
        assert_eq!(last_cell("| a | no — b |  "), "no — b");
    }
}
