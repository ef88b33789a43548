//! The protocol of Schaefer (2020, § 11.5) on SegComp-style images: per method a grid search
//! on the training images maximizing the mean fraction f of correctly segmented planes (the
//! thesis searches `e` and `d` of PPE this way and the parameters of MSAC and PEAC
//! "analogously"), then the best cell on the test images, scored by the Hoover et al. (1996)
//! evaluator at 80 % overlap ([`crate::eval::planes::hoover_score`]).

use anyhow::Result;
use raypath_geometry::PointCloud;
use raypath_planes::{MsacParams, PeacParams, PpeParams};
use serde::{Deserialize, Serialize};

use crate::eval::EvalContext;
use crate::eval::planes::{
    HooverScore, Method, hoover_score, mean, msac_grid, peac_grid, ppe_grid,
};
use crate::table::{Table, fmt_num};

/// One image with its ground truth, real or simulated.
pub struct Image {
    /// `perc.test.N` or `sim.test.N`.
    pub name: String,
    /// The organized cloud (the Perceptron geometry of the reader).
    pub cloud: PointCloud,
    /// Ground-truth label per pixel (labels ≥ 10 are planes).
    pub gt: Vec<Option<u32>>,
    /// Ground-truth angles `(label, label, degrees)` between adjacent planes, when known.
    pub angles: Option<Vec<(u32, u32, f64)>>,
}

impl Image {
    /// Runs `method` and scores it.
    pub fn score(&self, method: &Method) -> Result<HooverScore> {
        let (seg, secs) = method.run(&self.cloud, &self.name)?;
        hoover_score(&self.gt, &seg, secs, self.angles.as_deref())
    }
}

/// The smallest plane PPE and MSAC report (and the smaller of the PEAC-style sizes): the
/// size under which the stand-in leaves a face unlabelled.
const MIN_PLANE: usize = 100;

/// The values of every searched parameter.
struct Axes {
    /// PPE `√e` (m); planes of at least [`MIN_PLANE`] rays, no post-processing (the thesis'
    /// algorithm). `PpeParams::segcomp` (√e = d = 20 mm) is the set without training images.
    ppe_sqrt_e: &'static [f64],
    /// PPE `d = l_max` (m).
    ppe_d: &'static [f64],
    /// PEAC-style block size (pixels).
    peac_block: &'static [usize],
    /// PEAC-style RMS tolerance (m; merges 1.5 ×).
    peac_tol: &'static [f64],
    /// PEAC-style depth discontinuity (share of the range).
    peac_disc: &'static [f64],
    /// PEAC-style smallest plane (rays).
    peac_min: &'static [usize],
    /// MSAC inlier distance (m); planes of at least [`MIN_PLANE`] rays.
    msac_dist: &'static [f64],
    /// MSAC remaining fraction.
    msac_remaining: &'static [f64],
}

const FULL: Axes = Axes {
    ppe_sqrt_e: &[0.028, 0.040, 0.056, 0.080, 0.113, 0.160],
    ppe_d: &[0.010, 0.020, 0.040],
    peac_block: &[10, 15],
    peac_tol: &[0.001, 0.0015, 0.002, 0.003],
    peac_disc: &[0.05, 0.1],
    peac_min: &[MIN_PLANE, 300],
    msac_dist: &[0.002, 0.004, 0.008],
    msac_remaining: &[0.01, 0.02, 0.05],
};

/// `--quick`: two cells per method.
const QUICK: Axes = Axes {
    ppe_sqrt_e: &[0.040, 0.080],
    ppe_d: &[0.020],
    peac_block: &[10],
    peac_tol: &[0.0015, 0.003],
    peac_disc: &[0.1],
    peac_min: &[MIN_PLANE],
    msac_dist: &[0.004, 0.008],
    msac_remaining: &[0.02],
};

fn axes(quick: bool) -> &'static Axes {
    if quick { &QUICK } else { &FULL }
}

/// The grids of PPE, the PEAC-style baseline and MSAC.
pub fn grids(quick: bool) -> [Vec<Method>; 3] {
    let a = axes(quick);
    let strip = |cells: Vec<(Method, String)>| cells.into_iter().map(|(m, _)| m).collect();
    [
        strip(ppe_grid(a.ppe_sqrt_e, a.ppe_d, &[MIN_PLANE], 0)),
        strip(peac_grid(a.peac_block, a.peac_tol, a.peac_disc, a.peac_min)),
        strip(msac_grid(a.msac_dist, a.msac_remaining, &[MIN_PLANE])),
    ]
}

/// The grids in words, for the report.
pub fn grid_text(quick: bool) -> String {
    let a = axes(quick);
    let mm = |v: &[f64]| v.iter().map(|x| mm(*x)).collect::<Vec<_>>().join(", ");
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let ints = |v: &[usize]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "PPE √e ∈ {{{}}} mm × d ∈ {{{}}} mm (planes ≥ {MIN_PLANE} rays, no post-processing: the \
         thesis' algorithm); PEAC-style block ∈ {{{}}} px × tolerance ∈ {{{}}} mm (merges 1.5 ×) \
         × discontinuity ∈ {{{}}} × planes ≥ {{{}}} rays; MSAC inlier distance ∈ {{{}}} mm × \
         remaining fraction ∈ {{{}}} (planes ≥ {MIN_PLANE} rays, 300 hypotheses){}",
        mm(a.ppe_sqrt_e),
        mm(a.ppe_d),
        ints(a.peac_block),
        mm(a.peac_tol),
        list(a.peac_disc),
        ints(a.peac_min),
        mm(a.msac_dist),
        list(a.msac_remaining),
        if quick {
            " (--quick: two cells per method)"
        } else {
            ""
        }
    )
}

/// Where the best cell of every searched method lies in its grid (parameters at the edge of
/// their range) and how close the next cells come.
pub fn edge_note(outcome: &Outcome, quick: bool) -> String {
    let a = axes(quick);
    let f64s = |v: &[usize]| v.iter().map(|&x| x as f64).collect::<Vec<f64>>();
    let mut parts = Vec::new();
    for (cells, chosen) in outcome.cells.iter().zip(&outcome.chosen) {
        if cells.is_empty() {
            continue;
        }
        let params: Vec<(&str, f64, Vec<f64>, bool)> = match chosen {
            Method::Ppe(p) => vec![
                ("√e", p.max_increment_m2.sqrt(), a.ppe_sqrt_e.to_vec(), true),
                ("d", p.l_max_m, a.ppe_d.to_vec(), true),
            ],
            Method::Peac(p) => vec![
                ("block size", p.block_size as f64, f64s(a.peac_block), false),
                ("tolerance", p.init_tol_m, a.peac_tol.to_vec(), true),
                (
                    "discontinuity",
                    p.discontinuity_rel,
                    a.peac_disc.to_vec(),
                    false,
                ),
                (
                    "smallest plane",
                    p.min_points as f64,
                    f64s(a.peac_min),
                    false,
                ),
            ],
            Method::Msac(p) => vec![
                (
                    "inlier distance",
                    p.max_distance_m,
                    a.msac_dist.to_vec(),
                    true,
                ),
                (
                    "remaining fraction",
                    p.remaining_fraction,
                    a.msac_remaining.to_vec(),
                    false,
                ),
            ],
        };
        let close =
            |x: f64, y: Option<&f64>| y.is_some_and(|y| (x - y).abs() <= 1e-9 * x.abs().max(1.0));
        let edges: Vec<String> = params
            .iter()
            .filter(|(_, _, axis, _)| axis.len() > 1)
            .filter_map(|(name, v, axis, metres)| {
                let shown = if *metres {
                    format!("{} mm", mm(*v))
                } else {
                    format!("{v}")
                };
                if close(*v, axis.last()) {
                    Some(format!("the largest {name} ({shown})"))
                } else if close(*v, axis.first()) {
                    Some(format!("the smallest {name} ({shown})"))
                } else {
                    None
                }
            })
            .collect();
        let top = cells.len().min(3);
        let spread = cells[0].f() - cells[top - 1].f();
        let place = if edges.is_empty() {
            "inside its grid".to_owned()
        } else {
            format!("at {} of its grid", edges.join(" and "))
        };
        parts.push(format!(
            "{} {place} (the best {top} cells within {spread:.1} points of f)",
            chosen.name()
        ));
    }
    if parts.is_empty() {
        String::new()
    } else {
        format!("Where the best cells lie: {}.", parts.join("; "))
    }
}

/// The parameters used without training images: the PPE preset and the baselines' SynPEB
/// parameters at the SegComp scale (millimetre tolerances).
pub fn untuned() -> [Method; 3] {
    [
        Method::Ppe(PpeParams::segcomp()),
        Method::Peac(PeacParams {
            init_tol_m: 0.003,
            merge_tol_m: 0.0045,
            discontinuity_rel: 0.05,
            ..PeacParams::synpeb()
        }),
        Method::Msac(MsacParams {
            max_distance_m: 0.004,
            min_points: MIN_PLANE,
            ..MsacParams::synpeb()
        }),
    ]
}

/// Metres as millimetres, without decimals unless they matter (`1.5`, `20`).
fn mm(metres: f64) -> String {
    let v = 1000.0 * metres;
    if (v - v.round()).abs() < 1e-6 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

/// The varied parameters of a cell, in millimetres.
pub fn label(method: &Method) -> String {
    match method {
        Method::Ppe(p) => format!(
            "√e {} mm, d {} mm",
            mm(p.max_increment_m2.sqrt()),
            mm(p.l_max_m)
        ),
        Method::Peac(p) => format!(
            "block {}, tol {} mm, disc {:.2}, min {}",
            p.block_size,
            mm(p.init_tol_m),
            p.discontinuity_rel,
            p.min_points
        ),
        Method::Msac(p) => format!(
            "dist {} mm, remaining {:.2}",
            mm(p.max_distance_m),
            p.remaining_fraction
        ),
    }
}

/// One grid cell and its scores on the training images.
#[derive(Serialize, Deserialize)]
pub struct Cell {
    /// The method and its parameters.
    pub method: Method,
    /// Per training image.
    pub scores: Vec<HooverScore>,
}

impl Cell {
    fn f(&self) -> f64 {
        mean(&self.scores, |s| s.f)
    }

    fn k(&self) -> f64 {
        mean(&self.scores, |s| s.k)
    }
}

/// What the protocol gives for one data set (serde: a unit's result carries it).
#[derive(Serialize, Deserialize)]
pub struct Outcome {
    /// Per method (PPE, PEAC-style, MSAC) the grid cells, best first (empty without
    /// training images).
    pub cells: [Vec<Cell>; 3],
    /// Per method the parameters run on the test images.
    pub chosen: [Method; 3],
    /// Per method the scores per test image.
    pub test: [Vec<HooverScore>; 3],
    /// Names of the test images.
    pub test_names: Vec<String>,
}

/// Grid search on `train` (the mean f, ties by the mean k, then the grid order), then the
/// best cell of every method on the `n_test` images `test_image(i)` (made one at a time);
/// without training images the `untuned` parameters. `tag` labels the progress bars.
pub fn run(
    ctx: &EvalContext,
    tag: &str,
    train: &[Image],
    n_test: usize,
    mut test_image: impl FnMut(usize) -> Result<Image>,
) -> Result<Outcome> {
    let mut cells: [Vec<Cell>; 3] = Default::default();
    let mut chosen = untuned();
    if !train.is_empty() {
        for ((grid, out), pick) in grids(ctx.quick)
            .into_iter()
            .zip(&mut cells)
            .zip(&mut chosen)
        {
            let bar = ctx.progress(
                (grid.len() * train.len()) as u64,
                &format!("{tag} {} grid", pick.name()),
            );
            for method in grid {
                let mut scores = Vec::with_capacity(train.len());
                for image in train {
                    scores.push(image.score(&method)?);
                    bar.inc(1);
                }
                out.push(Cell { method, scores });
            }
            bar.finish_and_clear();
            // Stable: equal cells keep the grid order.
            out.sort_by(|a, b| b.f().total_cmp(&a.f()).then(b.k().total_cmp(&a.k())));
            if let Some(best) = out.first() {
                *pick = best.method;
            }
        }
    }
    let mut test: [Vec<HooverScore>; 3] = Default::default();
    let mut test_names = Vec::with_capacity(n_test);
    let bar = ctx.progress(n_test as u64, &format!("{tag} test"));
    for i in 0..n_test {
        let image = test_image(i)?;
        for (method, scores) in chosen.iter().zip(&mut test) {
            scores.push(image.score(method)?);
        }
        test_names.push(image.name);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(Outcome {
        cells,
        chosen,
        test,
        test_names,
    })
}

/// The mean of `f` over the scores where it is finite (α is undefined on images without a
/// correctly detected adjacent pair).
fn mean_finite(scores: &[HooverScore], f: impl Fn(&HooverScore) -> f64) -> f64 {
    let v: Vec<f64> = scores.iter().map(f).filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The Hoover et al. (1996) figures of a segmentation, as the tables name them.
pub const HOOVER_COLUMNS: [&str; 8] = [
    "f [%]",
    "k [%]",
    "RMSE [mm]",
    "α [°]",
    "n_o",
    "n_u",
    "n_m",
    "n_s",
];

/// The header of [`results_rows`].
pub fn result_header() -> Vec<&'static str> {
    let mut header = vec![
        "data",
        "method",
        "parameters (best on train)",
        "images",
        "GT planes",
        "planes",
    ];
    header.extend(HOOVER_COLUMNS);
    header.extend(["time/image [s]", crate::eval::comparable::HEADER]);
    header
}

/// One row per method of `outcome` into `table` (header [`result_header`]): means over the
/// test images (α over the images where it is defined), median time.
pub fn results_rows(table: &mut Table, data: &str, outcome: &Outcome, comparable: &str) {
    for (method, scores) in outcome.chosen.iter().zip(&outcome.test) {
        let mut secs: Vec<f64> = scores.iter().map(|s| s.secs).collect();
        table.row([
            data.to_owned(),
            method.name().to_owned(),
            label(method),
            scores.len().to_string(),
            fmt_num(mean(scores, |s| s.gt), 1),
            fmt_num(mean(scores, |s| s.planes), 1),
            fmt_num(mean(scores, |s| s.f), 1),
            fmt_num(mean(scores, |s| s.k), 1),
            fmt_num(mean(scores, |s| s.rmse_mm), 2),
            fmt_num(mean_finite(scores, |s| s.alpha_deg), 1),
            fmt_num(mean(scores, |s| s.n_o), 1),
            fmt_num(mean(scores, |s| s.n_u), 1),
            fmt_num(mean(scores, |s| s.n_m), 1),
            fmt_num(mean(scores, |s| s.n_s), 1),
            fmt_num(crate::eval::median(&mut secs), 2),
            comparable.to_owned(),
        ]);
    }
}

/// The best `shown` cells of every method's grid (and how many cells there were).
pub fn grid_table(data: &str, outcome: &Outcome, shown: usize) -> Table {
    let mut table = Table::new([
        "data",
        "method",
        "rank",
        "cell",
        "train f [%]",
        "train k [%]",
        "RMSE [mm]",
        "n_o",
        "n_u",
        "n_m",
        "n_s",
        "used on test",
    ]);
    for cells in &outcome.cells {
        for (rank, cell) in cells.iter().enumerate().take(shown) {
            let s = &cell.scores;
            table.row([
                data.to_owned(),
                cell.method.name().to_owned(),
                format!("{} of {}", rank + 1, cells.len()),
                label(&cell.method),
                fmt_num(cell.f(), 1),
                fmt_num(cell.k(), 1),
                fmt_num(mean(s, |x| x.rmse_mm), 2),
                fmt_num(mean(s, |x| x.n_o), 1),
                fmt_num(mean(s, |x| x.n_u), 1),
                fmt_num(mean(s, |x| x.n_m), 1),
                fmt_num(mean(s, |x| x.n_s), 1),
                if rank == 0 { "**yes**" } else { "" }.to_owned(),
            ]);
        }
    }
    table
}

/// The PPE grid as a matrix of the mean training f: `√e` by rows, `d` by columns.
pub fn ppe_matrix(outcome: &Outcome) -> Option<Table> {
    let cells = &outcome.cells[0];
    let params: Vec<(f64, f64, f64)> = cells
        .iter()
        .filter_map(|c| match c.method {
            Method::Ppe(p) => Some((p.max_increment_m2.sqrt(), p.l_max_m, c.f())),
            _ => None,
        })
        .collect();
    if params.is_empty() {
        return None;
    }
    let mut es: Vec<f64> = params.iter().map(|p| p.0).collect();
    let mut ds: Vec<f64> = params.iter().map(|p| p.1).collect();
    for v in [&mut es, &mut ds] {
        v.sort_by(f64::total_cmp);
        v.dedup();
    }
    let best = params.first().map(|p| (p.0, p.1));
    let mut header = vec!["√e \\ d".to_owned()];
    header.extend(ds.iter().map(|d| format!("{} mm", mm(*d))));
    let mut table = Table::new(header);
    for e in &es {
        let mut row = vec![format!("{} mm", mm(*e))];
        for d in &ds {
            let cell =
                params
                    .iter()
                    .find(|p| p.0 == *e && p.1 == *d)
                    .map_or("–".to_owned(), |p| {
                        let v = fmt_num(p.2, 1);
                        if Some((p.0, p.1)) == best {
                            format!("**{v}**")
                        } else {
                            v
                        }
                    });
            row.push(cell);
        }
        table.row(row);
    }
    Some(table)
}

/// The results as JSON: per method the parameters, the means and the per-image scores.
pub fn json(outcome: &Outcome) -> serde_json::Value {
    let methods: Vec<serde_json::Value> = outcome
        .chosen
        .iter()
        .zip(&outcome.test)
        .zip(&outcome.cells)
        .map(|((method, scores), cells)| {
            serde_json::json!({
                "method": method.name(),
                "parameters": label(method),
                "images": scores.len(),
                "f": mean(scores, |s| s.f), "k": mean(scores, |s| s.k),
                "rmse_mm": mean(scores, |s| s.rmse_mm),
                "alpha_deg": mean_finite(scores, |s| s.alpha_deg),
                "n_o": mean(scores, |s| s.n_o), "n_u": mean(scores, |s| s.n_u),
                "n_m": mean(scores, |s| s.n_m), "n_s": mean(scores, |s| s.n_s),
                "gt_planes": mean(scores, |s| s.gt), "planes": mean(scores, |s| s.planes),
                "per_image_f": scores.iter().map(|s| s.f).collect::<Vec<_>>(),
                "grid": cells.iter().map(|c| serde_json::json!({
                    "cell": label(&c.method), "train_f": c.f(), "train_k": c.k(),
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    serde_json::json!({"test_images": outcome.test_names, "methods": methods})
}

/// The mean f of `method_index` on the test images.
pub fn test_f(outcome: &Outcome, method_index: usize) -> f64 {
    outcome
        .test
        .get(method_index)
        .map_or(f64::NAN, |s| mean(s, |x| x.f))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use raypath_sim::segcomp::{SegcompConfig, Split, generate_image};

    /// A small stand-in image (128 × 128 pixels of the same scenes) as the protocol sees it.
    fn image(split: Split, index: usize) -> Image {
        let config = SegcompConfig {
            rows: 128,
            cols: 128,
            min_region_pixels: 20,
            ..SegcompConfig::default()
        };
        let g = generate_image(&config, 5, split, index).unwrap();
        Image {
            cloud: g.cloud(&config.geometry),
            name: g.name,
            gt: g.labels.labels.into_iter().map(Some).collect(),
            angles: Some(
                g.angles
                    .pairs
                    .iter()
                    .map(|p| (p.label_a, p.label_b, p.angle_deg))
                    .collect(),
            ),
        }
    }

    #[test]
    fn segcomp_protocol_uses_the_best_training_cell_and_fills_its_tables() {
        let ctx = EvalContext {
            workspace_root: std::env::temp_dir(),
            data_dir: std::env::temp_dir(),
            quick: true,
            out_dir: std::env::temp_dir(),
        };
        let train = vec![image(Split::Train, 0)];
        let outcome = run(&ctx, "test", &train, 2, |i| Ok(image(Split::Test, i))).unwrap();
        for ((cells, chosen), grid) in outcome.cells.iter().zip(&outcome.chosen).zip(grids(true)) {
            assert_eq!(cells.len(), grid.len());
            assert_eq!(cells[0].method, *chosen);
            assert!(cells.windows(2).all(|w| w[0].f() >= w[1].f()));
        }
        assert_eq!(outcome.test_names, ["sim.test.0", "sim.test.1"]);
        assert!(outcome.test.iter().all(|s| s.len() == 2));
        // PPE finds planes in these images.
        assert!(test_f(&outcome, 0) > 0.0);
        let mut table = Table::new(result_header());
        results_rows(&mut table, "simulated", &outcome, "no — test");
        assert_eq!(table.to_markdown().unwrap().lines().count(), 5);
        assert!(grid_table("simulated", &outcome, 2).to_markdown().is_ok());
        assert!(ppe_matrix(&outcome).unwrap().to_markdown().is_ok());
        assert_eq!(json(&outcome)["methods"].as_array().unwrap().len(), 3);
        // Two cells per axis in the quick grids: every best cell lies on an edge.
        let note = edge_note(&outcome, true);
        assert!(
            note.contains("PPE at the") && note.contains("MSAC at the"),
            "{note}"
        );
        // Without training images: the untuned parameters, no grid.
        let untrained = run(&ctx, "test", &[], 1, |i| Ok(image(Split::Test, i))).unwrap();
        assert_eq!(untrained.chosen, untuned());
        assert!(untrained.cells.iter().all(Vec::is_empty));
        assert!(ppe_matrix(&untrained).is_none());
        assert!(edge_note(&untrained, true).is_empty());
    }
}
