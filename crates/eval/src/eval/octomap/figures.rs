//! The bar charts of the page (leaves and insertion time at M = 8), from the measurements.

use anyhow::Result;

use super::NAME;
use super::measure::SetInfo;
use super::plot;
use crate::eval::EvalContext;

/// One plotted configuration (M = 8).
struct PlotRow<'a> {
    data: &'a str,
    resolution_m: f64,
    endpoint: bool,
    /// Leaves: ours, OctoMap's pruned (NaN without OctoMap).
    leaves: [f64; 2],
    /// Insertion µs per point: ours, OctoMap's.
    insert_us: [f64; 2],
}

/// The runs at M = 8 of every set, as plotted.
fn plot_rows<'a>(sets: &[&'a SetInfo]) -> Vec<PlotRow<'a>> {
    let mut rows = Vec::new();
    for set in sets {
        let points = set.points.max(1) as f64;
        for run in set.runs.iter().filter(|r| r.m == 8) {
            let (ours, peer) = (&run.compared.ours, run.compared.peer.as_ref());
            rows.push(PlotRow {
                data: &set.name,
                resolution_m: run.resolution_m,
                endpoint: run.endpoint,
                leaves: [
                    ours.leaves as f64,
                    peer.map_or(f64::NAN, |p| p.leaves as f64),
                ],
                insert_us: [
                    ours.insert_secs / points * 1e6,
                    peer.map_or(f64::NAN, |p| p.insert_secs / points * 1e6),
                ],
            });
        }
    }
    rows
}

/// One panel per data set of `value` (ours, OctoMap's) over the resolutions.
fn panels(
    sets: &[&SetInfo],
    rows: &[PlotRow],
    value: &dyn Fn(&PlotRow) -> [f64; 2],
) -> Vec<plot::Panel> {
    let mut resolutions: Vec<f64> = rows.iter().map(|r| r.resolution_m).collect();
    resolutions.sort_by(f64::total_cmp);
    resolutions.dedup();
    sets.iter()
        .map(|set| plot::Panel {
            groups: resolutions
                .iter()
                .map(|&r| {
                    let mut bars = [None; 4];
                    for row in rows
                        .iter()
                        .filter(|row| row.data == set.name && (row.resolution_m - r).abs() < 1e-9)
                    {
                        let v = value(row);
                        let at = if row.endpoint { 2 } else { 0 };
                        bars[at] = Some(v[0]);
                        bars[at + 1] = Some(v[1]);
                    }
                    (format!("{r}"), bars)
                })
                .collect(),
        })
        .collect()
}

/// Draws the plots into `docs/results/octomap/`; returns file names and captions.
pub fn write(ctx: &EvalContext, sets: &[&SetInfo]) -> Result<Vec<(String, String)>> {
    let rows = plot_rows(sets);
    if rows.is_empty() {
        return Ok(Vec::new());
    }
    let dir = ctx.figure_dir(NAME)?;
    let names: Vec<&str> = sets.iter().map(|s| s.name.as_str()).collect();
    let legend = format!(
        "panels left to right: {}; groups: resolution r in m; bars: ours beam-based (dark blue), \
         OctoMap beam-based (dark orange), ours end-point (light blue), OctoMap end-point (light \
         orange); M = 8; log scale, labels are powers of ten",
        names.join(", ")
    );
    let mut out = Vec::new();
    let file = "leaves.png";
    plot::bar_chart(
        &dir.join(file),
        "leaves",
        &names,
        &panels(sets, &rows, &|r| r.leaves),
    )?;
    out.push((
        file.to_owned(),
        format!("Leaves, ours vs pruned OctoMap ({legend})."),
    ));
    let file = "insert_us_per_point.png";
    plot::bar_chart(
        &dir.join(file),
        "insertion time (µs per point)",
        &names,
        &panels(sets, &rows, &|r| r.insert_us),
    )?;
    out.push((
        file.to_owned(),
        format!("Insertion time per point in µs, fusion included ({legend})."),
    ));
    Ok(out)
}
