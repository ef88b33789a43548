//! `cargo xtask eval geometry`: throughput of the exact Amanatides–Woo traversal of
//! `raypath-geometry` in cells per second on one core, against a naive traversal measured in
//! the same run.
//!
//! The workloads are those of the Criterion benchmark `cargo bench -p raypath-geometry --bench
//! traversal` (same generator, same seeds):
//! * `3d/inside`: a 200³ grid of 0.1 m voxels; rays start inside it in uniformly random
//!   directions and hit at 0.5–30 m (10 % no-returns traced to the 30 m maximum range);
//! * `3d/outside`: the same grid; rays start on a 25 m sphere around it, aimed at random points
//!   inside, no-returns traced to 60 m (clipped on entry and exit);
//! * `2d/inside`: a 2000² grid of 0.1 m cells; rays start in its central 100 m square and hit
//!   at 0.5–50 m (10 % no-returns traced to 50 m).
//!
//! Each repetition traces every ray and sums the in-cell lengths (what a decay-rate map
//! accumulates); the table reports the median over repetitions of cells per second, by wall
//! clock and by the thread's own CPU time (from `/proc/thread-self/schedstat`, which excludes
//! time the thread waited for a core on a shared machine).

use std::hint::black_box;
use std::time::Instant;

use anyhow::{Result, ensure};
use nalgebra::{Unit, Vector3};
use raypath_geometry::testing::workloads::{
    grid2, grid3, rays_inside_2d, rays_inside_3d, rays_outside_3d,
};
use raypath_geometry::{Grid2, Grid3, Ray2, Ray3};

use super::{EvalContext, EvalReport, median};
use crate::table::{Table, fmt_num};

/// The aim for 3-D traversal on one core, cells per second.
const AIM_3D_CELLS_PER_SEC: f64 = 1e8;

/// The naive reference: from the current `t`, find the cell of a point a hair further along
/// the ray, divide to find where the ray leaves that cell's box, record the crossing in a
/// per-ray `Vec`, repeat. Straightforward and allocation-heavy, as a first implementation
/// would be; it may skip or repeat zero-length corner cells, which does not matter for timing.
fn naive_traverse<const N: usize>(
    grid_min: [f64; N],
    cell_size: f64,
    dims: [usize; N],
    origin: [f64; N],
    direction: [f64; N],
    t_start: f64,
    t_end: f64,
) -> Vec<(usize, f64, f64)> {
    const NUDGE_M: f64 = 1e-9;
    let mut crossings = Vec::new();
    let mut t = t_start;
    while t < t_end {
        let probe = (t + NUDGE_M).min(t_end);
        let mut index = 0;
        let mut stride = 1;
        let mut t_exit = t_end;
        for axis in 0..N {
            let position = origin[axis] + direction[axis] * probe;
            let cell = ((position - grid_min[axis]) / cell_size).floor();
            let cell = cell.clamp(0.0, (dims[axis] - 1) as f64);
            index += cell as usize * stride;
            stride *= dims[axis];
            if direction[axis] != 0.0 {
                let face = if direction[axis] > 0.0 {
                    cell + 1.0
                } else {
                    cell
                };
                let boundary = grid_min[axis] + face * cell_size;
                let t_face = (boundary - origin[axis]) / direction[axis];
                if t_face > t && t_face < t_exit {
                    t_exit = t_face;
                }
            }
        }
        crossings.push((index, t, t_exit));
        // Guarantee progress even where rounding puts the face behind the probe.
        t = t_exit.max(probe);
    }
    crossings
}

/// The clipped interval of a segment, as the optimized traversal computes it.
fn clip3(grid: &Grid3, ray: &Ray3, length: f64) -> Option<(f64, f64)> {
    let clip = grid
        .bounds()
        .clip_segment(&ray.origin, &ray.direction, 0.0, length)?;
    (clip.1 > clip.0).then_some(clip)
}

fn clip2(grid: &Grid2, ray: &Ray2, length: f64) -> Option<(f64, f64)> {
    let clip = grid
        .bounds()
        .clip_segment(&ray.origin, &ray.direction, 0.0, length)?;
    (clip.1 > clip.0).then_some(clip)
}

/// Result of tracing a batch once: cells visited and the summed lengths.
struct Pass {
    cells: usize,
    length_m: f64,
}

fn fast3(grid: &Grid3, rays: &[Ray3], max_range_m: f64) -> Pass {
    let mut pass = Pass {
        cells: 0,
        length_m: 0.0,
    };
    for ray in rays {
        let (cells, length) = grid
            .traverse_ray(ray, max_range_m)
            .fold((0usize, 0.0f64), |(n, sum), c| (n + 1, sum + c.length()));
        pass.cells += cells;
        pass.length_m += length;
    }
    pass
}

fn fast2(grid: &Grid2, rays: &[Ray2], max_range_m: f64) -> Pass {
    let mut pass = Pass {
        cells: 0,
        length_m: 0.0,
    };
    for ray in rays {
        let (cells, length) = grid
            .traverse_ray(ray, max_range_m)
            .fold((0usize, 0.0f64), |(n, sum), c| (n + 1, sum + c.length()));
        pass.cells += cells;
        pass.length_m += length;
    }
    pass
}

fn naive3(grid: &Grid3, rays: &[Ray3], max_range_m: f64) -> Pass {
    let mut pass = Pass {
        cells: 0,
        length_m: 0.0,
    };
    let min: [f64; 3] = grid.origin().coords.into();
    for ray in rays {
        let Some((t0, t1)) = clip3(grid, ray, ray.range.traced_length(max_range_m)) else {
            continue;
        };
        let direction: &Unit<Vector3<f64>> = &ray.direction;
        let crossings = naive_traverse(
            min,
            grid.cell_size(),
            grid.dims(),
            ray.origin.coords.into(),
            direction.into_inner().into(),
            t0,
            t1,
        );
        pass.cells += crossings.len();
        pass.length_m += crossings.iter().map(|c| c.2 - c.1).sum::<f64>();
    }
    pass
}

fn naive2(grid: &Grid2, rays: &[Ray2], max_range_m: f64) -> Pass {
    let mut pass = Pass {
        cells: 0,
        length_m: 0.0,
    };
    let min: [f64; 2] = grid.origin().coords.into();
    for ray in rays {
        let Some((t0, t1)) = clip2(grid, ray, ray.range.traced_length(max_range_m)) else {
            continue;
        };
        let crossings = naive_traverse(
            min,
            grid.cell_size(),
            grid.dims(),
            ray.origin.coords.into(),
            ray.direction.into_inner().into(),
            t0,
            t1,
        );
        pass.cells += crossings.len();
        pass.length_m += crossings.iter().map(|c| c.2 - c.1).sum::<f64>();
    }
    pass
}

/// On-CPU time of the calling thread in seconds (Linux), `None` elsewhere.
fn thread_cpu_secs() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = stat.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// The 1-minute load average, to judge how shared the machine was.
fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Medians of one implementation on one workload.
struct Timing {
    cells: usize,
    length_m: f64,
    wall_cells_per_sec: f64,
    cpu_cells_per_sec: f64,
    wall_secs: Vec<f64>,
}

/// Runs `pass` once to warm up, then `repetitions` timed repetitions. Each repetition runs
/// `pass` often enough to last at least `min_repetition_secs`, so that the CPU-time reading
/// (which the kernel updates at scheduler ticks) is accurate.
fn time(repetitions: usize, min_repetition_secs: f64, mut pass: impl FnMut() -> Pass) -> Timing {
    let start = Instant::now();
    let warm = black_box(pass());
    let warm_secs = start.elapsed().as_secs_f64().max(1e-6);
    let passes = (min_repetition_secs / warm_secs).ceil().clamp(1.0, 1e6) as usize;
    let mut wall = Vec::with_capacity(repetitions);
    let mut cpu = Vec::with_capacity(repetitions);
    for _ in 0..repetitions {
        let cpu_start = thread_cpu_secs();
        let start = Instant::now();
        for _ in 0..passes {
            black_box(pass());
        }
        let wall_secs = start.elapsed().as_secs_f64() / passes as f64;
        if let (Some(a), Some(b)) = (cpu_start, thread_cpu_secs()) {
            cpu.push((b - a) / passes as f64);
        }
        wall.push(wall_secs);
    }
    let wall_secs = wall.clone();
    let cells = warm.cells as f64;
    Timing {
        cells: warm.cells,
        length_m: warm.length_m,
        wall_cells_per_sec: cells / median(&mut wall),
        cpu_cells_per_sec: cells / median(&mut cpu),
        wall_secs,
    }
}

/// One row of the report: a workload timed with both implementations.
struct Case {
    name: &'static str,
    grid: &'static str,
    rays: usize,
    fast: Timing,
    naive: Timing,
}

/// `results` of `target/eval/geometry.json` (keys as the fields; a JSON object's keys are
/// written sorted).
#[derive(serde::Serialize)]
struct GeometryResults {
    repetitions: usize,
    aim_3d_cells_per_sec: f64,
    load_average_before: Option<f64>,
    load_average_after: Option<f64>,
    cases: Vec<CaseResult>,
}

/// One workload of [`GeometryResults`]: medians of the fast and the naive traversal.
#[derive(serde::Serialize)]
struct CaseResult {
    case: &'static str,
    grid: &'static str,
    rays: usize,
    cells: usize,
    traced_length_m: f64,
    median_cells_per_sec_wall: f64,
    median_cells_per_sec_cpu: f64,
    wall_secs_per_pass: Vec<f64>,
    naive_cells: usize,
    naive_median_cells_per_sec_wall: f64,
    naive_median_cells_per_sec_cpu: f64,
    naive_wall_secs_per_pass: Vec<f64>,
}

impl CaseResult {
    fn of(case: &Case) -> Self {
        Self {
            case: case.name,
            grid: case.grid,
            rays: case.rays,
            cells: case.fast.cells,
            traced_length_m: case.fast.length_m,
            median_cells_per_sec_wall: case.fast.wall_cells_per_sec,
            median_cells_per_sec_cpu: case.fast.cpu_cells_per_sec,
            wall_secs_per_pass: case.fast.wall_secs.clone(),
            naive_cells: case.naive.cells,
            naive_median_cells_per_sec_wall: case.naive.wall_cells_per_sec,
            naive_median_cells_per_sec_cpu: case.naive.cpu_cells_per_sec,
            naive_wall_secs_per_pass: case.naive.wall_secs.clone(),
        }
    }
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let rays_per_case = if ctx.quick { 10_000 } else { 100_000 };
    let repetitions = if ctx.quick { 5 } else { 7 };
    let min_repetition_secs = if ctx.quick { 0.05 } else { 0.25 };
    let load_before = load_average();

    let (grid3, grid2) = (grid3(), grid2());
    let inside3 = rays_inside_3d(rays_per_case, 1);
    let outside3 = rays_outside_3d(rays_per_case, 2);
    let inside2 = rays_inside_2d(rays_per_case, 3);

    let progress = ctx.progress(6, "geometry");
    let mut cases = Vec::new();
    for (name, rays, max_range) in [
        ("3d/inside", &inside3, 30.0),
        ("3d/outside", &outside3, 60.0),
    ] {
        let fast = time(repetitions, min_repetition_secs, || {
            fast3(&grid3, rays, max_range)
        });
        progress.inc(1);
        let naive = time(repetitions, min_repetition_secs, || {
            naive3(&grid3, rays, max_range)
        });
        progress.inc(1);
        cases.push(Case {
            name,
            grid: "200³ × 0.1 m",
            rays: rays.len(),
            fast,
            naive,
        });
    }
    let fast = time(repetitions, min_repetition_secs, || {
        fast2(&grid2, &inside2, 50.0)
    });
    progress.inc(1);
    let naive = time(repetitions, min_repetition_secs, || {
        naive2(&grid2, &inside2, 50.0)
    });
    progress.inc(1);
    progress.finish_and_clear();
    cases.push(Case {
        name: "2d/inside",
        grid: "2000² × 0.1 m",
        rays: inside2.len(),
        fast,
        naive,
    });
    let load_after = load_average();

    // Both implementations must cover the same total length: the clipped segments.
    for case in &cases {
        let relative = (case.fast.length_m - case.naive.length_m).abs() / case.fast.length_m;
        ensure!(
            relative < 1e-9,
            "{}: traversal and naive reference disagree on the traced length ({} vs {} m)",
            case.name,
            case.fast.length_m,
            case.naive.length_m
        );
    }

    let conditions = Conditions {
        repetitions,
        min_repetition_secs,
        quick: ctx.quick,
        load_before,
        load_after,
        cores: std::thread::available_parallelism().map_or(1, usize::from),
    };
    report(&cases, &conditions)
}

/// How the cases were timed, for the page.
struct Conditions {
    repetitions: usize,
    min_repetition_secs: f64,
    quick: bool,
    /// 1-minute load average before and after the timing.
    load_before: Option<f64>,
    load_after: Option<f64>,
    /// Cores available to the process.
    cores: usize,
}

/// The page and the JSON of the timed `cases`.
fn report(cases: &[Case], conditions: &Conditions) -> Result<EvalReport> {
    let &Conditions {
        repetitions,
        min_repetition_secs,
        quick,
        load_before,
        load_after,
        cores,
    } = conditions;
    let mut table = Table::new([
        "case",
        "grid",
        "rays",
        "cells visited",
        "cells/ray",
        "median cells/s (wall)",
        "median cells/s (CPU)",
        "naive median cells/s (wall)",
        "speed-up",
        "aim ≥ 1e8 cells/s (3-D)",
    ]);
    for case in cases {
        let aim = if case.name.starts_with("3d") {
            if case.fast.wall_cells_per_sec >= AIM_3D_CELLS_PER_SEC {
                "met"
            } else if case.fast.cpu_cells_per_sec >= AIM_3D_CELLS_PER_SEC {
                "met in CPU time"
            } else {
                "missed"
            }
        } else {
            "—"
        };
        table.row([
            case.name.to_owned(),
            case.grid.to_owned(),
            case.rays.to_string(),
            case.fast.cells.to_string(),
            fmt_num(case.fast.cells as f64 / case.rays as f64, 1),
            format!("{:.3e}", case.fast.wall_cells_per_sec),
            format!("{:.3e}", case.fast.cpu_cells_per_sec),
            format!("{:.3e}", case.naive.wall_cells_per_sec),
            format!(
                "{:.1}×",
                case.fast.wall_cells_per_sec / case.naive.wall_cells_per_sec
            ),
            aim.to_owned(),
        ]);
    }

    let fmt_load = |l: Option<f64>| l.map_or("unknown".to_owned(), |l| format!("{l:.2}"));
    let markdown = format!(
        "Exact Amanatides–Woo traversal (`Grid3::traverse_ray`, `Grid2::traverse_ray`) on one \
         thread: every ray is traced and its in-cell lengths summed. Median of {repetitions} \
         repetitions{quick} (each repeats the batch for at least {min_repetition_secs} s); \
         \"CPU\" divides by the thread's own on-CPU time, which excludes \
         waiting for a core. The naive reference (per step: locate the cell of a point just past \
         the current `t`, divide to find the cell exit, push to a per-ray `Vec`) runs on the same \
         rays in the same process; both cover the same total length (checked to 1e-9).\n\n\
         {table}\n\
         Load average (1 min) before/after: {before}/{after} on {cores} cores (other jobs share \
         the machine; wall-clock rates drop when they do).\n\n\
         Reproduce with Criterion on the identical workloads (same generator and seeds): \
         `cargo bench -p raypath-geometry --bench traversal`.\n",
        quick = if quick {
            ", --quick: 10 000 rays per case"
        } else {
            ", 100 000 rays per case"
        },
        table = table.to_markdown()?,
        before = fmt_load(load_before),
        after = fmt_load(load_after),
    );

    let results = GeometryResults {
        repetitions,
        aim_3d_cells_per_sec: AIM_3D_CELLS_PER_SEC,
        load_average_before: load_before,
        load_average_after: load_after,
        cases: cases.iter().map(CaseResult::of).collect(),
    };
    Ok(EvalReport {
        name: "geometry",
        title: "Exact ray traversal throughput (cells per second, one core)".to_owned(),
        markdown,
        json: serde_json::to_value(&results)?,
        headline: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(cells: usize, wall: f64, cpu: f64) -> Timing {
        Timing {
            cells,
            length_m: 1234.5,
            wall_cells_per_sec: wall,
            cpu_cells_per_sec: cpu,
            wall_secs: vec![0.01, 0.02],
        }
    }

    fn case(name: &'static str, cells: usize, fast: (f64, f64), naive_wall: f64) -> Case {
        Case {
            name,
            grid: "200³ × 0.1 m",
            rays: 1000,
            fast: timing(cells, fast.0, fast.1),
            naive: timing(cells + 10, naive_wall, naive_wall),
        }
    }

    fn row<'a>(md: &'a str, case: &str) -> Vec<&'a str> {
        md.lines()
            .find(|l| l.starts_with(&format!("| {case} ")))
            .unwrap()
            .split('|')
            .map(str::trim)
            .collect()
    }

    /// Rates, speed-ups, the 3-D aim met by wall clock, by CPU time only or missed, the
    /// run's conditions and the JSON.
    #[test]
    fn report_from_known_timings() {
        let cases = [
            case("3d/inside", 12_500, (2.5e8, 3e8), 5e7),
            case("3d/outside", 8_000, (5e7, 1.2e8), 2e7),
            case("3d/slow", 4_000, (5e7, 9e7), 5e7),
            case("2d/inside", 3_000, (9e7, 9.5e7), 3e7),
        ];
        let conditions = Conditions {
            repetitions: 7,
            min_repetition_secs: 0.25,
            quick: false,
            load_before: Some(0.5),
            load_after: None,
            cores: 2,
        };
        let report = report(&cases, &conditions).unwrap();
        let md = &report.markdown;
        assert_eq!(
            &row(md, "3d/inside")[1..11],
            [
                "3d/inside",
                "200³ × 0.1 m",
                "1000",
                "12500",
                "12.5",
                "2.500e8",
                "3.000e8",
                "5.000e7",
                "5.0×",
                "met"
            ]
        );
        assert_eq!(row(md, "3d/outside")[9], "2.5×");
        assert_eq!(row(md, "3d/outside")[10], "met in CPU time");
        assert_eq!(row(md, "3d/slow")[9], "1.0×");
        assert_eq!(row(md, "3d/slow")[10], "missed");
        assert_eq!(row(md, "2d/inside")[5], "3.0");
        assert_eq!(row(md, "2d/inside")[10], "—");
        assert!(
            md.contains(
                "Median of 7 repetitions, 100 000 rays per case (each repeats the batch for at \
                 least 0.25 s)"
            ),
            "{md}"
        );
        assert!(
            md.contains("Load average (1 min) before/after: 0.50/unknown on 2 cores"),
            "{md}"
        );
        assert!(md.ends_with("`cargo bench -p raypath-geometry --bench traversal`.\n"));

        let json = &report.json;
        assert_eq!(json["repetitions"], 7);
        assert_eq!(json["aim_3d_cells_per_sec"], 1e8);
        assert_eq!(json["load_average_before"], 0.5);
        assert!(json["load_average_after"].is_null());
        let first = &json["cases"][0];
        assert_eq!(first["case"], "3d/inside");
        assert_eq!(first["cells"], 12_500);
        assert_eq!(first["naive_cells"], 12_510);
        assert_eq!(first["traced_length_m"], 1234.5);
        assert_eq!(first["median_cells_per_sec_cpu"], 3e8);
        assert_eq!(first["naive_median_cells_per_sec_wall"], 5e7);
        assert_eq!(first["wall_secs_per_pass"][1], 0.02);
        assert_eq!(json["cases"].as_array().unwrap().len(), 4);
    }

    #[test]
    fn quick_report_names_its_ray_count() {
        let conditions = Conditions {
            repetitions: 5,
            min_repetition_secs: 0.05,
            quick: true,
            load_before: None,
            load_after: Some(1.234),
            cores: 8,
        };
        let md = report(&[], &conditions).unwrap().markdown;
        assert!(
            md.contains("Median of 5 repetitions, --quick: 10 000 rays per case (each repeats the batch for at least 0.05 s)"),
            "{md}"
        );
        assert!(md.contains("before/after: unknown/1.23 on 8 cores"), "{md}");
    }
}
