//! `cargo xtask eval sim`: what each simulated data set contains, its statistics beside the
//! real samples and the thesis, checks that raypath-io reads every file, and pictures.

mod realism;

pub use realism::gap_note;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use raypath_geometry::Range;
use raypath_io::pcd::{self, ReadOptions};
use raypath_io::sequence::{
    LaserChoice, PlanarOptions, PlanarSource, SweepOptions, SweepSequence, open_planar,
};
use raypath_sim::datasets::SETS;
use serde_json::Value;

use super::{EvalContext, EvalReport, comparable};
use crate::generate;
use crate::render::{TopDown, colormap, label_color};
use crate::table::{Table, fmt_num};

/// A generated set on disk with its bookkeeping.
struct SetOnDisk {
    name: &'static str,
    about: &'static str,
    dir: PathBuf,
    info: Value,
}

impl SetOnDisk {
    fn stat(&self, path: &str) -> Option<&Value> {
        path.split('.')
            .try_fold(&self.info["stats"], |v, key| v.get(key))
    }

    fn num(&self, path: &str) -> f64 {
        self.stat(path).and_then(Value::as_f64).unwrap_or(f64::NAN)
    }
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let mut sets = Vec::new();
    let mut skipped = Vec::new();
    for spec in SETS {
        if let Some(required) = spec.requires
            && raypath_io::data::find(required).is_none()
        {
            skipped.push(format!(
                "`{}` (needs `{required}` in RAYPATH_DATA)",
                spec.name
            ));
            continue;
        }
        let dir = generate::ensure(spec.name, ctx.quick)?;
        let text = std::fs::read_to_string(dir.join("set.json"))
            .with_context(|| format!("reading {}/set.json", dir.display()))?;
        let mut info: Value = serde_json::from_str(&text)?;
        // Timings live beside set.json (same seed, same bytes); shown with the statistics.
        if let Ok(text) = std::fs::read_to_string(dir.join(generate::TIMING_FILE))
            && let (Ok(Value::Object(timing)), Some(stats)) = (
                serde_json::from_str::<Value>(&text),
                info.get_mut("stats").and_then(Value::as_object_mut),
            )
        {
            stats.extend(timing);
        }
        sets.push(SetOnDisk {
            name: spec.name,
            about: spec.about,
            dir,
            info,
        });
    }

    // Whether raypath-io reads all of each set.
    let bar = ctx.progress(sets.len() as u64, "reading sets");
    let mut readability = Vec::new();
    for set in &sets {
        readability.push(check_readable(set)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let real = RealFigures::read(&sets, ctx);
    let mut realism_md = String::new();
    let realism = realism::run(ctx, &mut realism_md)?;
    let figures = ctx.figure_dir("sim")?;
    let mut pictures_of_sets = Vec::new();
    for set in &sets {
        pictures_of_sets.extend(pictures(set, &figures)?);
    }
    report(&Measured {
        sets,
        skipped,
        readability,
        real,
        realism_md,
        realism,
        pictures: pictures_of_sets,
    })
}

/// What `run` found: the sets, their checks, the real figures beside them, the realism
/// section and the pictures written.
struct Measured {
    sets: Vec<SetOnDisk>,
    /// Sets not generated, with the reason.
    skipped: Vec<String>,
    /// Per set, as [`check_readable`] returns it.
    readability: Vec<(usize, usize, Vec<String>)>,
    real: RealFigures,
    /// The realism section's markdown.
    realism_md: String,
    /// The realism section's JSON.
    realism: Value,
    /// `(caption, file name)` of the pictures in the figure directory.
    pictures: Vec<(String, String)>,
}

/// The page and the JSON of what `run` found.
fn report(m: &Measured) -> Result<EvalReport> {
    let sets = &m.sets;
    let mut md = String::from(
        "Simulated data sets written by `raypath-sim` (`cargo xtask datasets generate`) in the \
         real formats, read back here through `raypath-io` exactly like real data. **Every row \
         of this page is simulated**, except the columns and rows marked *real*, which are \
         measured on the real samples in `RAYPATH_DATA` or quoted from the thesis.\n\n",
    );

    // What each set holds and whether raypath-io reads all of it.
    let mut table = Table::new([
        "set",
        "stands in for",
        "files",
        "MB",
        "mode",
        "raypath info",
    ]);
    let mut readability = Vec::new();
    for (set, (readable, total, failures)) in sets.iter().zip(&m.readability) {
        readability.push(serde_json::json!({"set": set.name, "readable": readable, "data_files": total, "failures": failures}));
        table.row([
            format!("`{}`", set.name),
            set.about.to_owned(),
            set.info["files"].as_array().map_or(0, Vec::len).to_string(),
            fmt_num(set.info["bytes"].as_f64().unwrap_or(0.0) / 1e6, 1),
            if set.info["quick"].as_bool() == Some(true) {
                "quick"
            } else {
                "full"
            }
            .to_owned(),
            format!("{readable}/{total} files"),
        ]);
    }
    md.push_str("## The sets\n\n");
    md.push_str(&table.to_markdown()?);
    md.push_str(
        "\nEvery data file is summarized by raypath-io as `raypath info` does; data files are everything but the ground-truth JSON \
         files (world descriptions, polygon vertices, corridor runs) and SemanticKITTI-style \
         `.label` files, which are not sensor formats raypath reads. KITTI- and NCLT-style \
         sets are also read as whole directories (`raypath info <set>`). Same seed, same bytes: \
         every set carries `SHA256SUMS`; `cargo xtask datasets generate --quick` twice gives \
         identical sums (tested in `crates/sim/tests`).\n",
    );
    if !m.skipped.is_empty() {
        md.push_str(&format!("\nSkipped: {}.\n", m.skipped.join(", ")));
    }

    md.push_str("\n## Statistics beside the real data and the thesis\n\n");
    md.push_str(&comparison_table(sets, &m.real)?.to_markdown()?);

    md.push_str("\n## Realism: real KITTI frames beside simulated frames at the same places\n\n");
    md.push_str(&m.realism_md);

    md.push_str("\n## Pictures\n\n");
    for (caption, file) in &m.pictures {
        md.push_str(&format!("**{caption}**\n\n![{caption}](sim/{file})\n\n"));
    }

    let json = serde_json::json!({
        "sets": sets.iter().map(|s| serde_json::json!({
            "name": s.name, "dir": s.dir.display().to_string(), "quick": s.info["quick"],
            "bytes": s.info["bytes"], "stats": s.info["stats"],
        })).collect::<Vec<_>>(),
        "readability": readability,
        "skipped": m.skipped,
        "realism": m.realism,
    });
    Ok(EvalReport {
        name: "sim",
        title: "Simulated data sets: contents, statistics and pictures".into(),
        markdown: md,
        json,
        headline: None,
    })
}

/// Reads every data file of a set (and the directory, for KITTI/NCLT layouts) with
/// raypath-io: `(readable, data files, failures)`.
fn check_readable(set: &SetOnDisk) -> Result<(usize, usize, Vec<String>)> {
    let mut failures = Vec::new();
    let files = set.info["files"].as_array().cloned().unwrap_or_default();
    let mut data_files = 0;
    let mut readable = 0;
    for entry in &files {
        let Some(relative) = entry["path"].as_str() else {
            continue;
        };
        // Ground-truth JSON and SemanticKITTI label files are not sensor formats.
        if relative.ends_with(".json") || relative.ends_with(".label") {
            continue;
        }
        data_files += 1;
        match raypath_io::summarize(&set.dir.join(relative)) {
            Ok(_) => readable += 1,
            Err(e) => failures.push(e.to_string()),
        }
    }
    if matches!(set.name, "urban-kitti" | "urban-nclt" | "semi-kitti")
        && let Err(e) = raypath_io::summarize(&set.dir)
    {
        failures.push(e.to_string());
    }
    Ok((readable, data_files, failures))
}

/// The "comparable" cell of the SynPEB crop rows.
const SYNPEB_CROP_COMPARABLE: &str = "no — crops of our simulated rooms vs the one crop of the \
     published SynPEB sample: other scenes";

/// The real figures set beside the simulated ones, each read only when its set is present.
struct RealFigures {
    /// Scans, beams and mean hit range of the real Intel log (beside `indoor`).
    intel: Option<(usize, usize, f64)>,
    /// The real SynPEB sample (beside `synpeb`).
    synpeb: Option<RealSynpeb>,
}

impl RealFigures {
    fn read(sets: &[SetOnDisk], ctx: &EvalContext) -> Self {
        let present = |name: &str| sets.iter().any(|s| s.name == name);
        Self {
            intel: if present("indoor") {
                real_log_stats(&ctx.data("carmen/corrected/intel-corrected.log.gz"))
            } else {
                None
            },
            synpeb: if present("synpeb") {
                real_synpeb(ctx)
            } else {
                None
            },
        }
    }
}

/// Real-sample figures: the SynPEB sample and the corrected CARMEN logs.
fn comparison_table(sets: &[SetOnDisk], real_figures: &RealFigures) -> Result<Table> {
    let mut table = Table::new([
        "set",
        "quantity",
        "simulated",
        "real / thesis",
        "source of the right column",
        comparable::HEADER,
    ]);
    let find = |name: &str| sets.iter().find(|s| s.name == name);
    if let Some(s) = find("polygons") {
        table.row([
            "polygons",
            "scans × rays",
            &format!("{} × {}", s.num("scans"), s.num("rays_per_scan")),
            "260 × 360",
            "thesis ch. 10 protocol",
            &comparable::yes("simulated in both: the thesis' protocol parameter"),
        ]);
        table.row([
            "polygons",
            "radial noise σ (m)",
            &fmt_num(s.num("range_noise_std_m"), 4),
            "0.03",
            "thesis ch. 10 protocol",
            &comparable::yes("simulated in both: the thesis' protocol parameter"),
        ]);
    }
    if let Some(s) = find("indoor") {
        let intel = &real_figures.intel;
        for world in ["office", "lab", "hall"] {
            if s.stat(world).is_none() {
                continue;
            }
            table.row([
                "indoor".to_owned(),
                format!("{world}: scans, beams, mean range (m)"),
                format!(
                    "{} × {}, {}",
                    s.num(&format!("{world}.scans")),
                    s.num(&format!("{world}.beams_per_scan")),
                    fmt_num(s.num(&format!("{world}.range_m.mean")), 2)
                ),
                intel.as_ref().map_or("—".into(), |(scans, beams, mean)| {
                    format!("{scans} × {beams}, {}", fmt_num(*mean, 2))
                }),
                "real: intel-corrected.log.gz".to_owned(),
                comparable::no(&format!(
                    "simulated {world} world vs the real Intel lab log: other building, simulated \
                     laser; scale only"
                )),
            ]);
            table.row([
                "indoor".to_owned(),
                format!("{world}: odometry drift per metre"),
                fmt_num(s.num(&format!("{world}.odometry_drift.per_metre")), 4),
                "—".into(),
                "configurable (odometry alphas)".into(),
                comparable::no("no real or thesis figure beside it"),
            ]);
        }
    }
    if let Some(s) = find("corridor") {
        table.row([
            "corridor",
            "mean / variance of μ (reflection)",
            &format!(
                "{} / {}",
                fmt_num(s.num("reflection.truth_mean"), 3),
                fmt_num(s.num("reflection.truth_variance"), 4)
            ),
            "0.5 / 0.0833",
            "U(0, 1), thesis §8.5.1",
            &comparable::yes("simulated in both: sample moments vs the thesis' distribution"),
        ]);
        table.row([
            "corridor",
            "mean / variance of λ (decay rate)",
            &format!(
                "{} / {}",
                fmt_num(s.num("decay-rate.truth_mean"), 3),
                fmt_num(s.num("decay-rate.truth_variance"), 3)
            ),
            "1 / 1",
            "Gamma(1, 1), thesis §8.5.1",
            &comparable::yes("simulated in both: sample moments vs the thesis' distribution"),
        ]);
    }
    if let Some(s) = find("synpeb") {
        let real = &real_figures.synpeb;
        table.row([
            "synpeb",
            "planes per scan (≥ 10 pixels)",
            &fmt_num(s.num("full_scans.planes_per_scan_min_10_pixels.mean"), 1),
            "42.6",
            "thesis §11 (SynPEB)",
            &comparable::no(
                "our SynPEB-style rooms vs the thesis' SynPEB scans: same kind of synthetic \
                 scene, other generator",
            ),
        ]);
        table.row([
            "synpeb".to_owned(),
            "planes in the 100 × 100 crop of the sample's window".into(),
            fmt_num(s.num("crop_100x100_at_row_col_100.planes_per_scan.mean"), 1),
            real.as_ref().map_or("—".into(), |r| r.planes.to_string()),
            "real: synpeb-sample-100x100.pcd".into(),
            SYNPEB_CROP_COMPARABLE.to_owned(),
        ]);
        table.row([
            "synpeb".to_owned(),
            "median range of the crop (m)".into(),
            fmt_num(
                s.num("crop_100x100_at_row_col_100.range_m.median_of_scan_medians"),
                2,
            ),
            real.as_ref()
                .map_or("—".into(), |r| fmt_num(r.median_range_m, 2)),
            "real: synpeb-sample-100x100.pcd".into(),
            SYNPEB_CROP_COMPARABLE.to_owned(),
        ]);
        table.row([
            "synpeb".to_owned(),
            "plane-pixel fraction (crop)".into(),
            fmt_num(
                s.num("crop_100x100_at_row_col_100.plane_pixel_fraction.mean"),
                3,
            ),
            real.as_ref()
                .map_or("—".into(), |r| fmt_num(r.plane_fraction, 3)),
            "real: synpeb-sample-100x100.pcd".into(),
            SYNPEB_CROP_COMPARABLE.to_owned(),
        ]);
    }
    for (name, lidar, real) in [
        ("urban-kitti", "HDL-64E", "≈ 120 000 (KITTI)"),
        ("semi-kitti", "HDL-64E", "≈ 120 000 (KITTI)"),
        ("urban-nclt", "HDL-32E", "≈ 50 000–70 000 (NCLT)"),
    ] {
        if let Some(s) = find(name) {
            table.row([
                name.to_owned(),
                format!("{lidar} points per scan"),
                fmt_num(s.num("scans.points_per_scan_mean"), 0),
                real.to_owned(),
                "published sensor figures".into(),
                comparable::no(
                    "our simulated streets vs the sensor's nominal figure for real scans \
                     (no-return shares differ, see the realism section)",
                ),
            ]);
            table.row([
                name.to_owned(),
                "simulated rays per second (2 cores)".into(),
                format!("{:.2e}", s.num("rays_per_s")),
                "≥ 2e6 (aim)".into(),
                "raypath's own aim".into(),
                comparable::no("an aim, not a thesis or peer figure"),
            ]);
        }
    }
    if let Some(s) = find("semi-kitti") {
        table.row([
            "semi-kitti",
            "poles placed / in the real map",
            &format!(
                "{} / {}",
                s.num("poles_placed.total"),
                s.num("poles_in_input")
            ),
            &format!("{} (real)", s.num("poles_in_input")),
            "real: kitti-poles/07/poles.csv",
            &comparable::yes("the real pole map is the simulator's input"),
        ]);
    }
    Ok(table)
}

/// The front-laser scans of a CARMEN log.
fn front_laser(path: &Path) -> Result<Box<dyn PlanarSource>> {
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    Ok(open_planar(path, &options)?)
}

/// Scans, beams and mean hit range of a real corrected log.
fn real_log_stats(path: &Path) -> Option<(usize, usize, f64)> {
    let frames = front_laser(path).ok()?;
    let (mut scans, mut beams, mut sum, mut hits) = (0, 0, 0.0, 0usize);
    for frame in frames.flatten() {
        scans += 1;
        beams = frame.scan.len();
        for i in 0..frame.scan.len() {
            if let Range::Hit(r) = frame.scan.range(i) {
                sum += r;
                hits += 1;
            }
        }
    }
    (scans > 0).then(|| (scans, beams, sum / hits.max(1) as f64))
}

struct RealSynpeb {
    planes: usize,
    median_range_m: f64,
    plane_fraction: f64,
}

fn real_synpeb(ctx: &EvalContext) -> Option<RealSynpeb> {
    let path = ctx.data("planes/synpeb-sample-100x100.pcd");
    let read = pcd::read_pcd(&path, &ReadOptions::synpeb()).ok()?;
    let labels = read.cloud.label.as_ref()?;
    let mut planes: Vec<u32> = labels.iter().copied().filter(|&l| l >= 10).collect();
    let plane_fraction = planes.len() as f64 / labels.len().max(1) as f64;
    planes.sort_unstable();
    planes.dedup();
    let mut ranges: Vec<f64> = read
        .cloud
        .points
        .iter()
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .map(|p| f64::from(p.coords.norm()))
        .collect();
    Some(RealSynpeb {
        planes: planes.len(),
        median_range_m: super::median(&mut ranges),
        plane_fraction,
    })
}

/// Pictures of a set: `(caption, file name)`.
fn pictures(set: &SetOnDisk, dir: &Path) -> Result<Vec<(String, String)>> {
    let mut out = Vec::new();
    match set.name {
        "polygons" => {
            let file = "polygons.png";
            if polygons_picture(set, &dir.join(file))? {
                out.push((
                    "polygons: ground-truth polygon (blue) and the noisy scan (red), first scan"
                        .into(),
                    file.into(),
                ));
            }
        }
        "indoor" => {
            let log = set.dir.join("office-corrected.log.gz");
            let file = "indoor-office.png";
            if log_picture(&log, &dir.join(file))? {
                out.push(("indoor: the office world rendered from its corrected log (hits, grey) and the path (red)".into(), file.into()));
            }
        }
        "synpeb" => {
            let file = "synpeb-scan.png";
            if synpeb_picture(set, &dir.join(file))? {
                out.push(("synpeb: first test scan, range (left, near = dark) and plane labels (right; grey = curved, black = none)".into(), file.into()));
            }
        }
        "urban-kitti" | "semi-kitti" => {
            let top = format!("{}-top.png", set.name);
            if kitti_top_down(set, &dir.join(&top))? {
                out.push((format!("{}: every 5th scan in the world frame (grey), trajectory (red), ground-truth poles (blue)", set.name), top));
            }
            if set.name == "urban-kitti" {
                let image = "urban-kitti-range.png";
                if kitti_range_image(set, &dir.join(image))? {
                    out.push(("urban-kitti: first HDL-64E scan as a range image (64 rows, each drawn 4 pixels high; near = dark)".into(), image.into()));
                }
            }
        }
        _ => {}
    }
    Ok(out)
}

fn polygons_picture(set: &SetOnDisk, path: &Path) -> Result<bool> {
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(set.dir.join("polygons.json"))?)?;
    let Some(vertices) = truth["polygons"][0]["vertices"].as_array() else {
        return Ok(false);
    };
    let vertices: Vec<(f64, f64)> = vertices
        .iter()
        .filter_map(|v| Some((v[0].as_f64()?, v[1].as_f64()?)))
        .collect();
    let Some(scan) = front_laser(&set.dir.join("polygons.log"))?.flatten().next() else {
        return Ok(false);
    };
    let points: Vec<(f64, f64)> = scan
        .scan
        .points(scan.world_from_laser)
        .map(|p| (p.x, p.y))
        .collect();
    let mut bounds = points.clone();
    bounds.extend(&vertices);
    let Some(mut top) = TopDown::fit(&bounds, 0.0, 0.01, 600.0) else {
        return Ok(false);
    };
    for (i, &a) in vertices.iter().enumerate() {
        top.line(a, vertices[(i + 1) % vertices.len()], [40, 90, 200]);
    }
    for &(x, y) in &points {
        top.dot(x, y, 1, [220, 40, 40]);
    }
    top.dot(0.0, 0.0, 3, [0, 0, 0]);
    top.legend("ground-truth polygon", [40, 90, 200]);
    top.legend("scan endpoints", [220, 40, 40]);
    top.legend("sensor", [0, 0, 0]);
    top.save(path)?;
    Ok(true)
}

fn log_picture(log: &Path, path: &Path) -> Result<bool> {
    let mut hits = Vec::new();
    let mut trajectory = Vec::new();
    for frame in front_laser(log)?.flatten() {
        trajectory.push((frame.world_from_laser.x(), frame.world_from_laser.y()));
        hits.extend(
            frame
                .scan
                .points(frame.world_from_laser)
                .map(|p| (p.x, p.y)),
        );
    }
    let Some(mut top) = TopDown::fit(&hits, 0.001, 0.05, 900.0) else {
        return Ok(false);
    };
    for &(x, y) in &hits {
        top.hit(x, y);
    }
    for pair in trajectory.windows(2) {
        top.line(pair[0], pair[1], [220, 40, 40]);
    }
    top.legend("path", [220, 40, 40]);
    top.save(path)?;
    Ok(true)
}

fn synpeb_picture(set: &SetOnDisk, path: &Path) -> Result<bool> {
    let Some(file) = first_file(set, "test/", ".pcd") else {
        return Ok(false);
    };
    let read = pcd::read_pcd(&set.dir.join(file), &ReadOptions::synpeb())?;
    let cloud = &read.cloud;
    let (w, h) = (cloud.width as u32, cloud.height as u32);
    let mut image = image::RgbImage::new(2 * w, h);
    let labels = cloud.label.clone().unwrap_or_default();
    for row in 0..h {
        for col in 0..w {
            let i = (row * w + col) as usize;
            let p = cloud.points[i];
            let range = f64::from(p.coords.norm());
            let color = if range.is_finite() {
                colormap(range / 8.0)
            } else {
                [0, 0, 0]
            };
            image.put_pixel(col, row, image::Rgb(color));
            let label = labels.get(i).copied().unwrap_or(0);
            image.put_pixel(w + col, row, image::Rgb(label_color(label)));
        }
    }
    image
        .save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(true)
}

fn first_file<'a>(set: &'a SetOnDisk, prefix: &str, suffix: &str) -> Option<&'a str> {
    set.info["files"]
        .as_array()?
        .iter()
        .filter_map(|f| f["path"].as_str())
        .find(|p| p.starts_with(prefix) && p.ends_with(suffix))
}

/// The sequence directory of a KITTI-layout set (`sequences/NN`).
fn sequence_dir(set: &SetOnDisk) -> Option<PathBuf> {
    let sequences = set.dir.join("sequences");
    let mut entries: Vec<_> = std::fs::read_dir(&sequences)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    entries.into_iter().find(|p| p.is_dir())
}

fn kitti_top_down(set: &SetOnDisk, path: &Path) -> Result<bool> {
    let Some(dir) = sequence_dir(set) else {
        return Ok(false);
    };
    let sequence = SweepSequence::open(&dir, &SweepOptions::default())?;
    let Some(world_from_velo) = sequence.reference.as_deref() else {
        return Ok(false);
    };
    let mut hits = Vec::new();
    for (i, pose) in world_from_velo.iter().enumerate().step_by(5) {
        let scan = sequence.sweep(i)?;
        for p in scan.points.iter().step_by(4) {
            let q = pose.transform_point(&p.cast::<f64>());
            hits.push((q.x, q.y));
        }
    }
    let poles = raypath_io::point_csv::PointCsv::read(&dir.join("poles.csv"))
        .map(|csv| csv.points().iter().map(|p| (p.x, p.y)).collect::<Vec<_>>())
        .unwrap_or_default();
    let Some(mut top) = TopDown::fit(&hits, 0.002, 0.1, 1200.0) else {
        return Ok(false);
    };
    for &(x, y) in &hits {
        top.hit(x, y);
    }
    for pair in world_from_velo.windows(2) {
        let (a, b) = (pair[0].translation(), pair[1].translation());
        top.line((a.x, a.y), (b.x, b.y), [220, 40, 40]);
    }
    for &(x, y) in &poles {
        top.dot(x, y, 2, [40, 90, 200]);
    }
    top.legend("trajectory", [220, 40, 40]);
    top.legend("ground-truth poles", [40, 90, 200]);
    top.save(path)?;
    Ok(true)
}

fn kitti_range_image(set: &SetOnDisk, path: &Path) -> Result<bool> {
    let Some(dir) = sequence_dir(set) else {
        return Ok(false);
    };
    let sequence = SweepSequence::open(&dir, &SweepOptions::default())?;
    if sequence.is_empty() {
        return Ok(false);
    }
    let cloud = sequence.sweep(0)?;
    // One row per laser: each point goes to the laser of nearest elevation (the HDL-64E's
    // elevations are not evenly spaced, so a uniform spherical grid would leave empty rows).
    let mut elevations = raypath_sim::lidar3::Lidar3::hdl64e().elevations_rad;
    elevations.sort_by(|a, b| b.total_cmp(a));
    let (rows, cols, scale) = (elevations.len(), 1024usize, 4usize);
    let mut nearest = vec![f64::INFINITY; rows * cols];
    for p in &cloud.points {
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        let range = (x * x + y * y + z * z).sqrt();
        if !range.is_finite() || range == 0.0 {
            continue;
        }
        let elevation = z.atan2(x.hypot(y));
        let row = elevations
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - elevation).abs().total_cmp(&(b.1 - elevation).abs()))
            .map_or(0, |(i, _)| i);
        // Column 0 looks backwards-left, the middle forwards (azimuth decreasing to the right).
        let azimuth = y.atan2(x);
        let col =
            (((std::f64::consts::PI - azimuth) / std::f64::consts::TAU) * cols as f64) as usize;
        let cell = &mut nearest[row * cols + col.min(cols - 1)];
        *cell = cell.min(range);
    }
    let mut png = image::RgbImage::new(cols as u32, (rows * scale) as u32);
    for row in 0..rows {
        for col in 0..cols {
            let r = nearest[row * cols + col];
            let color = if r.is_finite() {
                colormap((r / 60.0).sqrt())
            } else {
                [0, 0, 0]
            };
            for k in 0..scale {
                png.put_pixel(col as u32, (row * scale + k) as u32, image::Rgb(color));
            }
        }
    }
    png.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    fn set(name: &'static str, about: &'static str, info: Value) -> SetOnDisk {
        SetOnDisk {
            name,
            about,
            dir: PathBuf::from(format!("/sim/{name}")),
            info,
        }
    }

    fn sets() -> Vec<SetOnDisk> {
        vec![
            set(
                "polygons",
                "thesis ch. 10 scans",
                json!({
                    "files": [{"path": "polygons.log"}, {"path": "polygons.json"}],
                    "bytes": 1_500_000, "quick": true,
                    "stats": {"scans": 260, "rays_per_scan": 360, "range_noise_std_m": 0.03},
                }),
            ),
            set(
                "indoor",
                "CARMEN logs",
                json!({
                    "files": [{"path": "office-corrected.log.gz"}],
                    "bytes": 250_000, "quick": false,
                    "stats": {"office": {
                        "scans": 50, "beams_per_scan": 180, "range_m": {"mean": 3.456},
                        "odometry_drift": {"per_metre": 0.0123},
                    }},
                }),
            ),
            set(
                "synpeb",
                "SynPEB",
                json!({
                    "files": [], "bytes": 0,
                    "stats": {
                        "full_scans": {"planes_per_scan_min_10_pixels": {"mean": 40.04}},
                        "crop_100x100_at_row_col_100": {
                            "planes_per_scan": {"mean": 6.5},
                            "range_m": {"median_of_scan_medians": 3.25},
                            "plane_pixel_fraction": {"mean": 0.5},
                        },
                    },
                }),
            ),
        ]
    }

    fn measured(real: RealFigures) -> Measured {
        Measured {
            sets: sets(),
            skipped: vec!["`semi-kitti` (needs `kitti-poles/07` in RAYPATH_DATA)".into()],
            readability: vec![
                (1, 1, Vec::new()),
                (0, 1, vec!["bad gzip".into()]),
                (0, 0, Vec::new()),
            ],
            real,
            realism_md: "REALISM SECTION\n".into(),
            realism: json!({"skipped": "no real KITTI frames"}),
            pictures: vec![("polygons: a caption".into(), "polygons.png".into())],
        }
    }

    /// The cells of the line that starts with `| set ` and has `quantity` in its second column.
    fn row<'a>(md: &'a str, set: &str, quantity: &str) -> Vec<&'a str> {
        md.lines()
            .filter(|l| l.starts_with(&format!("| {set} ")))
            .map(|l| l.split('|').map(str::trim).collect::<Vec<_>>())
            .find(|cells| cells[2] == quantity)
            .unwrap_or_else(|| panic!("no row {set} / {quantity} in {md}"))
    }

    /// Known sets, checks and real figures: the sets table, the comparison rows, the
    /// sections in order and the JSON.
    #[test]
    fn report_from_known_sets() {
        let real = RealFigures {
            intel: Some((100, 180, 4.5678)),
            synpeb: Some(RealSynpeb {
                planes: 7,
                median_range_m: 3.2,
                plane_fraction: 0.456,
            }),
        };
        let report = report(&measured(real)).unwrap();
        let md = &report.markdown;
        assert!(md.starts_with("Simulated data sets written by `raypath-sim`"));

        let polygons = md.lines().find(|l| l.starts_with("| `polygons`")).unwrap();
        let cells: Vec<&str> = polygons.split('|').map(str::trim).collect();
        assert_eq!(
            &cells[1..7],
            [
                "`polygons`",
                "thesis ch. 10 scans",
                "2",
                "1.5",
                "quick",
                "1/1 files"
            ]
        );
        let indoor = md.lines().find(|l| l.starts_with("| `indoor`")).unwrap();
        assert!(
            indoor.contains("| full ") && indoor.contains("| 0/1 files"),
            "{indoor}"
        );
        assert!(md.contains("\nSkipped: `semi-kitti` (needs `kitti-poles/07` in RAYPATH_DATA).\n"));

        assert_eq!(row(md, "polygons", "scans × rays")[3], "260 × 360");
        assert_eq!(row(md, "polygons", "radial noise σ (m)")[3], "0.0300");
        let office = row(md, "indoor", "office: scans, beams, mean range (m)");
        assert_eq!(
            &office[3..6],
            [
                "50 × 180, 3.46",
                "100 × 180, 4.57",
                "real: intel-corrected.log.gz"
            ]
        );
        assert!(
            office[6].starts_with("no — simulated office world"),
            "{}",
            office[6]
        );
        assert_eq!(
            row(md, "indoor", "office: odometry drift per metre")[3],
            "0.0123"
        );
        assert_eq!(
            row(md, "synpeb", "planes per scan (≥ 10 pixels)")[3],
            "40.0"
        );
        let crop = row(
            md,
            "synpeb",
            "planes in the 100 × 100 crop of the sample's window",
        );
        assert_eq!(&crop[3..5], ["6.5", "7"]);
        assert_eq!(crop[6], SYNPEB_CROP_COMPARABLE);
        assert_eq!(
            &row(md, "synpeb", "median range of the crop (m)")[3..5],
            ["3.25", "3.20"]
        );
        assert_eq!(
            &row(md, "synpeb", "plane-pixel fraction (crop)")[3..5],
            ["0.500", "0.456"]
        );
        assert!(
            !md.contains("| corridor "),
            "no corridor set, no corridor rows"
        );

        assert!(md.contains(
            "## Realism: real KITTI frames beside simulated frames at the same places\n\nREALISM \
             SECTION\n\n## Pictures\n\n**polygons: a caption**\n\n![polygons: a caption](sim/polygons.png)\n\n"
        ), "{md}");

        let json = &report.json;
        assert_eq!(json["sets"][0]["name"], "polygons");
        assert_eq!(json["sets"][0]["dir"], "/sim/polygons");
        assert_eq!(json["sets"][0]["quick"], true);
        assert_eq!(json["sets"][1]["bytes"], 250_000);
        assert_eq!(json["sets"][0]["stats"]["rays_per_scan"], 360);
        assert_eq!(json["readability"][1]["set"], "indoor");
        assert_eq!(json["readability"][1]["readable"], 0);
        assert_eq!(json["readability"][1]["data_files"], 1);
        assert_eq!(json["readability"][1]["failures"][0], "bad gzip");
        assert_eq!(
            json["skipped"][0],
            "`semi-kitti` (needs `kitti-poles/07` in RAYPATH_DATA)"
        );
        assert_eq!(json["realism"]["skipped"], "no real KITTI frames");
    }

    /// Without the real samples the right column shows a dash.
    #[test]
    fn report_without_real_samples() {
        let real = RealFigures {
            intel: None,
            synpeb: None,
        };
        let md = report(&measured(real)).unwrap().markdown;
        assert_eq!(
            row(&md, "indoor", "office: scans, beams, mean range (m)")[4],
            "—"
        );
        let crop = row(
            &md,
            "synpeb",
            "planes in the 100 × 100 crop of the sample's window",
        );
        assert_eq!(crop[4], "—");
        assert_eq!(row(&md, "synpeb", "plane-pixel fraction (crop)")[4], "—");
        assert_eq!(row(&md, "polygons", "scans × rays")[4], "260 × 360");
    }
}
