//! `cargo xtask eval carmen-angles`: which beam-angle convention do old-format CARMEN scans
//! (`FLASER`, whose lines carry no angles) follow?
//!
//! Every scan of every corrected Radish log is projected with its reference (SLAM-corrected)
//! pose into a 5 cm grid under each candidate convention, and the map's sharpness is scored:
//!
//! * **occupied cells**: the number of distinct cells hit. With the right beam angles, a wall
//!   seen from many poses and bearings is hit in the same cells every time; a wrong angle
//!   model turns each beam by an error that depends on its index, so the same wall lands in
//!   different cells from different viewpoints and the map smears over more cells. All
//!   conventions project the same hits, so the counts compare directly; fewer is crisper.
//! * **entropy** of the hit histogram over cells (bits), `−Σ p log₂ p`: the same idea
//!   weighted by how often each cell is hit (the "crispness" criterion of point-cloud
//!   calibration, for example Sheehan, Harrison and Newman, ICRA 2011). Lower is crisper.
//!
//! The mirrored fan is a sanity check: it must lose by far.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rayon::prelude::*;
use raypath_io::carmen::{CarmenReader, FanConvention, Record};
use serde_json::json;

use super::stages::Staged;
use super::{EvalContext, EvalReport};
use crate::render::TopDown;
use crate::table::{Table, fmt_num};

/// Grid cell size of the sharpness score in metres.
const CELL_M: f64 = 0.05;
/// Every n-th scan with `--quick`.
const QUICK_STRIDE: usize = 4;
/// Largest side of a picture in pixels.
const PICTURE_PX: f64 = 1000.0;
/// Logs whose winning rendering is saved as a picture.
const PICTURED: [&str; 4] = ["intel", "aces", "freiburg-079", "csail"];

/// A candidate beam layout: a fan convention, optionally mirrored (beam 0 on the left).
#[derive(Clone, Copy, Debug)]
struct Candidate {
    name: &'static str,
    fan: FanConvention,
    mirrored: bool,
}

const CANDIDATES: [Candidate; 4] = [
    Candidate {
        name: "closed π/(n−1)",
        fan: FanConvention::Closed,
        mirrored: false,
    },
    Candidate {
        name: "half-open π/n",
        fan: FanConvention::HalfOpen,
        mirrored: false,
    },
    Candidate {
        name: "centered π/n",
        fan: FanConvention::Centered,
        mirrored: false,
    },
    Candidate {
        name: "closed, mirrored",
        fan: FanConvention::Closed,
        mirrored: true,
    },
];

impl Candidate {
    fn layout(self, n: usize) -> (f64, f64) {
        let (min, inc) = self.fan.layout(n, PI, None);
        if self.mirrored {
            (-min, -inc)
        } else {
            (min, inc)
        }
    }
}

/// One scan: the laser pose, the hits (beam index, range) and the reader's own layout.
struct Scan {
    pose: (f64, f64, f64),
    beams: usize,
    hits: Vec<(u32, f64)>,
    reader_layout: (f64, f64),
}

/// The sharpness of one rendering.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Score {
    cells: usize,
    entropy_bits: f64,
}

fn load(path: &Path, stride: usize) -> Result<Vec<Scan>> {
    let mut scans = Vec::new();
    let mut index = 0usize;
    for record in CarmenReader::open(path)? {
        let Record::Laser(laser) = record? else {
            continue;
        };
        index += 1;
        if (index - 1) % stride != 0 {
            continue;
        }
        let scan = &laser.scan;
        let hits = (0..scan.len())
            .filter_map(|i| scan.range(i).hit().map(|r| (i as u32, r)))
            .collect();
        let pose = &laser.world_from_laser;
        scans.push(Scan {
            pose: (pose.x(), pose.y(), pose.theta()),
            beams: scan.len(),
            hits,
            reader_layout: (scan.angle_min_rad, scan.angle_increment_rad),
        });
    }
    Ok(scans)
}

/// World-frame hit points of all scans under a layout (`None`: the reader's layout).
fn project(scans: &[Scan], candidate: Option<Candidate>) -> Vec<(f64, f64)> {
    project_with(scans, |scan| {
        candidate.map_or(scan.reader_layout, |c| c.layout(scan.beams))
    })
}

/// World-frame hit points of all scans, beam angles from `layout(scan)`.
fn project_with(scans: &[Scan], layout: impl Fn(&Scan) -> (f64, f64)) -> Vec<(f64, f64)> {
    let mut points = Vec::with_capacity(scans.iter().map(|s| s.hits.len()).sum());
    for scan in scans {
        let (min, inc) = layout(scan);
        let (x, y, theta) = scan.pose;
        for &(i, r) in &scan.hits {
            let a = theta + min + f64::from(i) * inc;
            points.push((x + r * a.cos(), y + r * a.sin()));
        }
    }
    points
}

fn cell_key(p: (f64, f64), cell_m: f64) -> u64 {
    // Offsetting by 2^31 keeps keys of negative cells ordered and distinct.
    let ix = ((p.0 / cell_m).floor() as i64 + (1 << 31)) as u64 & 0xffff_ffff;
    let iy = ((p.1 / cell_m).floor() as i64 + (1 << 31)) as u64 & 0xffff_ffff;
    (ix << 32) | iy
}

fn score(points: &[(f64, f64)]) -> Score {
    let mut keys: Vec<u64> = points.iter().map(|&p| cell_key(p, CELL_M)).collect();
    keys.sort_unstable();
    let total = keys.len() as f64;
    let (mut cells, mut entropy) = (0usize, 0.0);
    let mut start = 0;
    while start < keys.len() {
        let end = start
            + keys[start..]
                .iter()
                .take_while(|&&k| k == keys[start])
                .count();
        let p = (end - start) as f64 / total;
        entropy -= p * p.log2();
        cells += 1;
        start = end;
    }
    Score {
        cells,
        entropy_bits: entropy,
    }
}

/// Renders hit counts as a grayscale picture (white background, darker = more hits), north
/// up, at a cell size that keeps the larger side near `PICTURE_PX` pixels (5 cm at least).
/// The frame covers the 0.2–99.8 % quantiles of x and y, so a few hits through windows do
/// not shrink the building.
fn picture(points: &[(f64, f64)], path: &Path) -> Result<()> {
    let Some(mut top) = TopDown::fit(points, 0.002, CELL_M, PICTURE_PX) else {
        return Ok(());
    };
    for &(x, y) in points {
        top.hit(x, y);
    }
    top.save(path)
}

/// Offsets of the first and the last beam, in half nominal steps, tried by the sweep.
const SWEEP: [i32; 5] = [-2, -1, 0, 1, 2];

/// The nominal step 180°/(n − n mod 2): 1° for 180 and 181 beams, 0.5° for 360 and 361.
fn nominal_step(n: usize) -> f64 {
    PI / (n - n % 2).max(1) as f64
}

/// The fan whose first beam is at −90° + `first`·step/2 and whose last beam is at
/// −90° + (n−1)·step + `last`·step/2 (step = the nominal step).
fn swept_layout(n: usize, first: i32, last: i32) -> (f64, f64) {
    let step = nominal_step(n);
    let a0 = -PI / 2.0 + f64::from(first) * step / 2.0;
    let a1 = -PI / 2.0 + (n.max(2) - 1) as f64 * step + f64::from(last) * step / 2.0;
    (a0, (a1 - a0) / (n.max(2) - 1) as f64)
}

/// The sweep's best `(first, last)` offsets and their cells, and the cells at `(0, 0)`.
fn sweep(scans: &[Scan]) -> ((i32, i32), usize, usize) {
    let grid: Vec<(i32, i32)> = SWEEP
        .iter()
        .flat_map(|&f| SWEEP.iter().map(move |&l| (f, l)))
        .collect();
    let cells: Vec<usize> = grid
        .par_iter()
        .map(|&(f, l)| score(&project_with(scans, |s| swept_layout(s.beams, f, l))).cells)
        .collect();
    let best = (0..grid.len()).min_by_key(|&i| cells[i]).unwrap_or(0);
    let nominal = grid.iter().position(|&g| g == (0, 0)).unwrap_or(0);
    (grid[best], cells[best], cells[nominal])
}

/// One log's measurements: the result of one unit of the staged evaluation.
#[derive(serde::Serialize, serde::Deserialize)]
struct LogResult {
    sweep: ((i32, i32), usize, usize),
    log: String,
    beams: usize,
    scans: usize,
    hits: usize,
    scores: Vec<Score>,
    reader: Score,
    /// Pictures written for this log: (caption, file under the figure directory).
    pictures: Vec<(String, String)>,
}

/// The evaluation in stages: one unit per corrected log (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: "carmen-angles",
    units,
    run_unit,
    report: report_units,
};

fn log_dir(ctx: &EvalContext) -> PathBuf {
    ctx.data("carmen/corrected")
}

const SUFFIX: &str = "-corrected.log.gz";

/// The corrected logs, by name, sorted.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut logs: Vec<String> = std::fs::read_dir(log_dir(ctx))
        .map(|entries| {
            entries
                .flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    name.strip_suffix(SUFFIX).map(str::to_owned)
                })
                .collect()
        })
        .unwrap_or_default();
    logs.sort();
    Ok(logs)
}

fn stride(ctx: &EvalContext) -> usize {
    if ctx.quick { QUICK_STRIDE } else { 1 }
}

/// Scores one log under every candidate and draws its pictures.
fn run_unit(ctx: &EvalContext, log: &str) -> Result<serde_json::Value> {
    let path = log_dir(ctx).join(format!("{log}{SUFFIX}"));
    let figures = ctx.figure_dir("carmen-angles")?;
    let scans = load(&path, stride(ctx)).with_context(|| format!("reading {}", path.display()))?;
    let beams = scans.first().map_or(0, |s| s.beams);
    let hits = scans.iter().map(|s| s.hits.len()).sum();
    let scores: Vec<Score> = CANDIDATES
        .par_iter()
        .map(|&c| score(&project(&scans, Some(c))))
        .collect();
    let reader = score(&project(&scans, None));
    let sweep = sweep(&scans);
    let mut pictures = Vec::new();
    if PICTURED.contains(&log) {
        let best = best_index(&scores);
        let file = format!("{log}-{}.png", CANDIDATES[best].fan.name());
        picture(
            &project(&scans, Some(CANDIDATES[best])),
            &figures.join(&file),
        )?;
        pictures.push((log.to_owned(), file));
        if log == "intel" {
            // The runner-up, for contrast.
            let second = runner_up(&scores, best);
            let file = format!("{log}-{}.png", CANDIDATES[second].fan.name());
            picture(
                &project(&scans, Some(CANDIDATES[second])),
                &figures.join(&file),
            )?;
            pictures.push((format!("{log} (runner-up)"), file));
        }
    }
    Ok(serde_json::to_value(LogResult {
        sweep,
        log: log.to_owned(),
        beams,
        scans: scans.len(),
        hits,
        scores,
        reader,
        pictures,
    })?)
}

/// The page from every log's result.
fn report_units(ctx: &EvalContext, units: &[(String, serde_json::Value)]) -> Result<EvalReport> {
    if units.is_empty() {
        let message = format!(
            "No corrected CARMEN logs in `{}`: nothing to evaluate (set RAYPATH_DATA).\n",
            log_dir(ctx).display()
        );
        eprintln!("{message}");
        return Ok(EvalReport {
            name: "carmen-angles",
            title: "CARMEN beam-angle convention (skipped: no data)".into(),
            markdown: message,
            json: json!({ "skipped": true }),
            headline: None,
        });
    }
    let results: Vec<LogResult> = units
        .iter()
        .map(|(log, value)| {
            serde_json::from_value(value.clone()).with_context(|| format!("result of {log}"))
        })
        .collect::<Result<_>>()?;
    let pictures: Vec<(String, String)> = results.iter().flat_map(|r| r.pictures.clone()).collect();
    report(&results, &pictures, stride(ctx))
}

fn best_index(scores: &[Score]) -> usize {
    (0..scores.len())
        .min_by_key(|&i| scores[i].cells)
        .unwrap_or(0)
}

fn runner_up(scores: &[Score], best: usize) -> usize {
    (0..scores.len())
        .filter(|&i| i != best)
        .min_by_key(|&i| scores[i].cells)
        .unwrap_or(0)
}

fn report(
    results: &[LogResult],
    pictures: &[(String, String)],
    stride: usize,
) -> Result<EvalReport> {
    let mut headers = vec![
        "log".to_owned(),
        "beams".into(),
        "scans".into(),
        "hits".into(),
    ];
    headers.extend(CANDIDATES.iter().map(|c| format!("{} cells", c.name)));
    headers.extend([
        "reader cells".into(),
        "winner (cells)".into(),
        "margin".into(),
    ]);
    headers.push("winner (entropy)".into());
    let mut cells_table = Table::new(headers);
    let mut entropy_headers = vec!["log".to_owned()];
    entropy_headers.extend(CANDIDATES.iter().map(|c| format!("{} bits", c.name)));
    entropy_headers.push("reader bits".into());
    let mut entropy_table = Table::new(entropy_headers);
    let mut sweep_table = Table::new([
        "log",
        "beams",
        "nominal step",
        "best first beam",
        "best last beam",
        "cells at best",
        "cells at −90° + i·step",
    ]);
    let mut json_logs = Vec::new();
    let mut reader_is_best = 0;
    let mut entropy_agrees = 0;
    for r in results {
        let best = best_index(&r.scores);
        let second = runner_up(&r.scores, best);
        let best_entropy = (0..r.scores.len())
            .min_by(|&a, &b| {
                r.scores[a]
                    .entropy_bits
                    .total_cmp(&r.scores[b].entropy_bits)
            })
            .unwrap_or(0);
        entropy_agrees += usize::from(best_entropy == best);
        reader_is_best += usize::from(r.reader.cells <= r.scores[best].cells);
        let margin = 100.0 * (r.scores[second].cells as f64 / r.scores[best].cells as f64 - 1.0);
        let mut row = vec![
            r.log.clone(),
            r.beams.to_string(),
            r.scans.to_string(),
            r.hits.to_string(),
        ];
        row.extend(r.scores.iter().map(|s| s.cells.to_string()));
        row.push(r.reader.cells.to_string());
        row.push(CANDIDATES[best].name.to_owned());
        row.push(format!("{}%", fmt_num(margin, 2)));
        row.push(CANDIDATES[best_entropy].name.to_owned());
        cells_table.row(row);
        let mut row = vec![r.log.clone()];
        row.extend(r.scores.iter().map(|s| fmt_num(s.entropy_bits, 4)));
        row.push(fmt_num(r.reader.entropy_bits, 4));
        entropy_table.row(row);
        let ((first, last), best_cells, nominal_cells) = r.sweep;
        let step_deg = nominal_step(r.beams).to_degrees();
        let offset = |k: i32| {
            let deg = f64::from(k) * step_deg / 2.0;
            if k == 0 {
                "nominal".to_owned()
            } else {
                format!("{deg:+}°")
            }
        };
        sweep_table.row([
            r.log.clone(),
            r.beams.to_string(),
            format!("{step_deg}°"),
            offset(first),
            offset(last),
            best_cells.to_string(),
            nominal_cells.to_string(),
        ]);
        json_logs.push(json!({
            "log": r.log,
            "beams": r.beams,
            "scans": r.scans,
            "hits": r.hits,
            "candidates": CANDIDATES.iter().zip(&r.scores).map(|(c, s)| json!({
                "name": c.name, "fan": c.fan.name(), "mirrored": c.mirrored,
                "cells": s.cells, "entropy_bits": s.entropy_bits,
            })).collect::<Vec<_>>(),
            "reader": { "cells": r.reader.cells, "entropy_bits": r.reader.entropy_bits },
            "winner_cells": CANDIDATES[best].name,
            "winner_entropy": CANDIDATES[best_entropy].name,
            "runner_up_margin_percent": margin,
            "sweep": { "best_first_half_steps": r.sweep.0.0, "best_last_half_steps": r.sweep.0.1,
                       "best_cells": r.sweep.1, "nominal_cells": r.sweep.2 },
        }));
    }
    let verdict = |odd: bool| {
        let subset: Vec<&LogResult> = results
            .iter()
            .filter(|r| (r.beams % 2 == 1) == odd)
            .collect();
        let mut wins = vec![0usize; CANDIDATES.len()];
        for r in &subset {
            wins[best_index(&r.scores)] += 1;
        }
        let top = (0..wins.len()).max_by_key(|&i| wins[i]).unwrap_or(0);
        (CANDIDATES[top].name, wins[top], subset.len())
    };
    let (even_name, even_wins, even_logs) = verdict(false);
    let (odd_name, odd_wins, odd_logs) = verdict(true);
    let mirrored = CANDIDATES.iter().position(|c| c.mirrored).unwrap_or(0);
    let mirror_penalty = results
        .iter()
        .map(|r| r.scores[mirrored].cells as f64 / r.scores[best_index(&r.scores)].cells as f64)
        .fold(f64::INFINITY, f64::min);
    let mut md = String::new();
    md.push_str(&format!(
        "Which beam angles do `FLASER` scans use? Their lines carry only the ranges; the \
         candidates spread `n` beams over 180° starting on the robot's right (REP-103, \
         counter-clockwise): **closed** `linspace(−90°, +90°, n)` (step 180°/(n−1)), \
         **half-open** step 180°/n from −90° (a 180-beam scan ends at +89°), **centered** step \
         180°/n symmetric about 0° (±89.5°), and the closed fan **mirrored** (beam 0 on the \
         left) as a sanity check. {} of each corrected log is projected with its \
         reference pose, and the hits are counted in a {:.0} cm grid.\n\n",
        if stride == 1 {
            "Every scan".to_owned()
        } else {
            format!("Every {stride}th scan")
        },
        CELL_M * 100.0
    ));
    md.push_str(
        "**Metric.** With the right angles a wall seen from many poses is hit in the same \
         cells every time; a wrong angle model turns beam `i` by an error that grows with `i`, \
         so one wall lands in different cells from different viewpoints and the map smears. \
         All candidates project the same hits, so the number of **occupied cells** compares \
         directly (fewer = crisper). The **entropy** of the hit histogram (`−Σ p log₂ p` over \
         cells; the crispness criterion of point-cloud calibration) weighs cells by their hits \
         and is reported as a cross-check. *margin* = how many more cells the runner-up \
         needs. *reader* = the layout `CarmenReader` produces by default \
         (`FanConvention::Auto`: closed for odd, half-open for even beam counts; a \
         `PARAM laser_front_laser_resolution` line, present in csail (0.5°) and fhw (1°), sets \
         the step).\n\n",
    );
    md.push_str("### Occupied 5 cm cells (fewer is crisper)\n\n");
    md.push_str(&cells_table.to_markdown()?);
    md.push_str("\n### Entropy of the hit histogram in bits (lower is crisper)\n\n");
    md.push_str(&entropy_table.to_markdown()?);
    md.push_str(
        "\n### Sweep of the first and last beam\n\nA finer check that the winner is not just \
         the least wrong of three guesses: the first and the last beam are moved in half \
         nominal steps (−1 to +1 step; nominal step 180°/(n − n mod 2), first beam at −90°) \
         and the fan in between is spread evenly, 25 layouts per log. \"nominal\" is the \
         `Auto` layout (beam `i` at −90° + i·step).\n\n",
    );
    md.push_str(&sweep_table.to_markdown()?);
    md.push_str(&format!(
        "\n**Verdict.** Even beam counts (180, 360): `{even_name}` wins {even_wins} of \
         {even_logs} logs. Odd beam counts (181, 361): `{odd_name}` wins {odd_wins} of \
         {odd_logs} logs. Either way the beams sit at multiples of the scanner's resolution \
         (1° or 0.5°) from −90°; the even-count logs lack the beam at +90°. The entropy picks \
         the same winner in {entropy_agrees} of {n} logs. The mirrored fan needs at least \
         {mirror_penalty:.2}× the cells of the winner in every log (the sanity check holds). The reader's default layout is as \
         crisp as the best candidate in {reader_is_best} of {n} logs.\n\n",
        n = results.len()
    ));
    if !pictures.is_empty() {
        md.push_str(
            "### Pictures\n\nThe winning rendering of a few logs (hit counts, north up; for \
             intel also the runner-up). Compare them with the map picture that ships beside \
             each log in the data set, ",
        );
        md.push_str(
            "`$RAYPATH_DATA/carmen/corrected/<log>-corrected.png` (not copied into this \
             repository). The renderings must show the same building, not mirrored.\n\n",
        );
        for (log, file) in pictures {
            md.push_str(&format!(
                "**{log}**: `{file}`\n\n![{log}](carmen-angles/{file})\n\n"
            ));
        }
    }
    Ok(EvalReport {
        name: "carmen-angles",
        title: "CARMEN beam-angle convention checked by map sharpness".into(),
        markdown: md,
        json: json!({
            "cell_m": CELL_M,
            "scan_stride": stride,
            "winner_even_beams": even_name,
            "winner_odd_beams": odd_name,
            "logs": json_logs,
        }),
        headline: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scores(cells: [usize; 4], bits: [f64; 4]) -> Vec<Score> {
        cells
            .iter()
            .zip(bits)
            .map(|(&cells, entropy_bits)| Score {
                cells,
                entropy_bits,
            })
            .collect()
    }

    /// The last cells of the markdown line of `log` in the table under `heading`.
    fn cells<'a>(md: &'a str, heading: &str, log: &str) -> Vec<&'a str> {
        let start = md.find(heading).unwrap();
        md[start..]
            .lines()
            .find(|l| l.starts_with(&format!("| {log} ")))
            .unwrap()
            .split('|')
            .map(str::trim)
            .collect()
    }

    /// Four points in two 5 cm cells, two hits each: two cells and one bit. A point just below
    /// zero falls in a cell of its own.
    #[test]
    fn score_counts_cells_and_entropy() {
        let s = score(&[(0.01, 0.01), (0.02, 0.04), (0.06, 0.01), (0.09, 0.02)]);
        assert_eq!(s.cells, 2);
        assert!((s.entropy_bits - 1.0).abs() < 1e-12, "{}", s.entropy_bits);
        let s = score(&[(0.01, 0.01), (-0.01, 0.01)]);
        assert_eq!(s.cells, 2);
        assert_eq!(score(&[]).cells, 0);
    }

    /// An even-count log won by the half-open fan and an odd-count log won by the closed fan
    /// (with the entropy disagreeing): the rows, the sweep, the verdict and the JSON.
    #[test]
    fn report_from_known_scores() {
        let results = [
            LogResult {
                sweep: ((0, -2), 99, 100),
                log: "even".into(),
                beams: 180,
                scans: 10,
                hits: 1000,
                scores: scores([120, 100, 110, 300], [7.0, 6.5, 6.8, 8.0]),
                reader: Score {
                    cells: 100,
                    entropy_bits: 6.5,
                },
                pictures: vec![],
            },
            LogResult {
                sweep: ((1, 0), 195, 200),
                log: "odd".into(),
                beams: 181,
                scans: 20,
                hits: 3000,
                scores: scores([200, 220, 210, 500], [7.2, 7.0, 7.1, 9.0]),
                reader: Score {
                    cells: 201,
                    entropy_bits: 7.25,
                },
                pictures: vec![],
            },
        ];
        let pictures = [("intel".to_owned(), "intel-half-open.png".to_owned())];
        let report = report(&results, &pictures, 4).unwrap();
        let md = &report.markdown;

        let even = cells(md, "### Occupied", "even");
        assert_eq!(
            &even[1..13],
            [
                "even",
                "180",
                "10",
                "1000",
                "120",
                "100",
                "110",
                "300",
                "100",
                "half-open π/n",
                "10.00%",
                "half-open π/n"
            ]
        );
        let odd = cells(md, "### Occupied", "odd");
        assert_eq!(odd[9], "201", "reader cells");
        assert_eq!(odd[10], "closed π/(n−1)");
        assert_eq!(odd[11], "5.00%");
        assert_eq!(odd[12], "half-open π/n", "the entropy's winner");

        let bits = cells(md, "### Entropy", "odd");
        assert_eq!(
            &bits[2..7],
            ["7.2000", "7.0000", "7.1000", "9.0000", "7.2500"]
        );

        let sweep = cells(md, "### Sweep", "even");
        assert_eq!(&sweep[3..8], ["1°", "nominal", "-1°", "99", "100"]);
        let sweep = cells(md, "### Sweep", "odd");
        assert_eq!(&sweep[4..6], ["+0.5°", "nominal"]);

        assert!(md.starts_with("Which beam angles do `FLASER` scans use?"));
        assert!(md.contains("Every 4th scan of each corrected log"), "{md}");
        assert!(md.contains("counted in a 5 cm grid"), "{md}");
        assert!(
            md.contains("`half-open π/n` wins 1 of 1 logs. Odd beam counts (181, 361): `closed π/(n−1)` wins 1 of 1 logs."),
            "{md}"
        );
        assert!(md.contains("same winner in 1 of 2 logs"), "{md}");
        assert!(md.contains("at least 2.50× the cells"), "{md}");
        assert!(
            md.contains("crisp as the best candidate in 1 of 2 logs"),
            "{md}"
        );
        assert!(md.contains(
            "**intel**: `intel-half-open.png`\n\n![intel](carmen-angles/intel-half-open.png)\n"
        ));

        let json = &report.json;
        assert_eq!(json["scan_stride"], 4);
        assert_eq!(json["cell_m"], 0.05);
        assert_eq!(json["winner_even_beams"], "half-open π/n");
        assert_eq!(json["winner_odd_beams"], "closed π/(n−1)");
        let odd = &json["logs"][1];
        assert_eq!(odd["log"], "odd");
        assert_eq!(odd["winner_cells"], "closed π/(n−1)");
        assert_eq!(odd["winner_entropy"], "half-open π/n");
        assert!((odd["runner_up_margin_percent"].as_f64().unwrap() - 5.0).abs() < 1e-9);
        assert_eq!(odd["candidates"][3]["fan"], "closed");
        assert_eq!(odd["candidates"][3]["mirrored"], true);
        assert_eq!(odd["candidates"][3]["cells"], 500);
        assert_eq!(odd["reader"]["cells"], 201);
        assert_eq!(odd["sweep"]["best_first_half_steps"], 1);
        assert_eq!(odd["sweep"]["best_last_half_steps"], 0);
        assert_eq!(odd["sweep"]["nominal_cells"], 200);
    }

    /// Every scan: the page says so and has no picture section without pictures.
    #[test]
    fn report_without_stride_or_pictures() {
        let results = [LogResult {
            sweep: ((0, 0), 10, 10),
            log: "one".into(),
            beams: 361,
            scans: 1,
            hits: 361,
            scores: scores([10, 11, 12, 40], [3.0, 3.1, 3.2, 5.0]),
            reader: Score {
                cells: 10,
                entropy_bits: 3.0,
            },
            pictures: vec![],
        }];
        let md = report(&results, &[], 1).unwrap().markdown;
        assert!(md.contains("Every scan of each corrected log"), "{md}");
        assert!(!md.contains("### Pictures"), "{md}");
        assert_eq!(cells(&md, "### Sweep", "one")[3], "0.5°");
        assert!(md.contains("Odd beam counts (181, 361): `closed π/(n−1)` wins 1 of 1 logs"));
    }
}
