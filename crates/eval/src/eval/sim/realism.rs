//! Simulator realism: every real KITTI frame beside a frame simulated by `raypath-sim` at the
//! same place of the same drive (the semi-synthetic KITTI world of the real pole map), compared
//! by points per ring, ranges, no-returns, intensity per SemanticKITTI class and pole points.

use std::fmt::Write;

use anyhow::Result;
use raypath_geometry::PointCloud;
use raypath_io::kitti::KittiSequence;
use raypath_sim::semi_kitti::SemiKittiDrive;
use serde_json::{Value, json};

use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// Seed of the simulated drives.
const SEED: u64 = 2020;
/// Classes whose mean intensity is compared (SemanticKITTI ids).
const CLASSES: [(u32, &str); 5] = [
    (40, "road"),
    (50, "building"),
    (70, "vegetation"),
    (10, "car"),
    (80, "pole"),
];
/// Range histogram: 1 m bins up to 120 m.
const RANGE_BINS: usize = 120;
/// Elevation histogram: 0.5° bins from −30° to +10°.
const ELEVATION_BINS: usize = 80;

/// Statistics of a set of frames (one sequence, real or simulated).
#[derive(Default)]
struct Stats {
    frames: usize,
    returns: usize,
    per_ring: Vec<f64>,
    elevation_hist: Vec<f64>,
    ranges: Vec<f64>,
    range_hist: Vec<f64>,
    class_intensity: Vec<(f64, usize)>,
    intensity_hist: Vec<f64>,
    pole_points: usize,
    trunk_points: usize,
}

impl Stats {
    fn new(rings: usize) -> Self {
        Self {
            per_ring: vec![0.0; rings],
            elevation_hist: vec![0.0; ELEVATION_BINS],
            range_hist: vec![0.0; RANGE_BINS],
            class_intensity: vec![(0.0, 0); CLASSES.len()],
            intensity_hist: vec![0.0; 50],
            ..Self::default()
        }
    }

    /// Adds the returns of one frame (sensor frame); `elevations` are the rings' nominal
    /// elevations, sorted ascending.
    fn add(&mut self, cloud: &PointCloud, labels: Option<&[u32]>, elevations: &[f64]) {
        self.frames += 1;
        for i in (0..cloud.len()).filter(|&i| cloud.is_valid(i)) {
            let p = cloud.point_f64(i);
            let range = p.coords.norm();
            if range.is_nan() || range <= 0.0 {
                continue;
            }
            self.returns += 1;
            let elevation = p.z.atan2(p.x.hypot(p.y));
            self.per_ring[nearest(elevations, elevation)] += 1.0;
            let bin = ((elevation.to_degrees() + 30.0) * 2.0).floor();
            self.elevation_hist[bin.clamp(0.0, (ELEVATION_BINS - 1) as f64) as usize] += 1.0;
            self.ranges.push(range);
            self.range_hist[(range as usize).min(RANGE_BINS - 1)] += 1.0;
            let intensity = cloud
                .intensity
                .as_ref()
                .map_or(f64::NAN, |v| f64::from(v[i]));
            if intensity.is_finite() {
                let bin = ((intensity.clamp(0.0, 1.0) * 50.0) as usize).min(49);
                self.intensity_hist[bin] += 1.0;
            }
            let Some(class) = labels.and_then(|l| l.get(i)).map(|l| l & 0xffff) else {
                continue;
            };
            if let Some(k) = CLASSES.iter().position(|c| c.0 == class)
                && intensity.is_finite()
            {
                self.class_intensity[k].0 += intensity;
                self.class_intensity[k].1 += 1;
            }
            self.pole_points += usize::from(class == 80);
            self.trunk_points += usize::from(class == 71);
        }
    }

    fn quantile(&mut self, q: f64) -> f64 {
        self.ranges.sort_by(f64::total_cmp);
        let k = ((self.ranges.len().max(1) - 1) as f64 * q).round() as usize;
        self.ranges.get(k).copied().unwrap_or(f64::NAN)
    }

    fn per_frame(&self, n: usize) -> f64 {
        n as f64 / self.frames.max(1) as f64
    }

    fn class_mean(&self, k: usize) -> f64 {
        let (sum, n) = self.class_intensity[k];
        if n == 0 { f64::NAN } else { sum / n as f64 }
    }
}

/// Index of the value of sorted `values` nearest to `x`.
fn nearest(values: &[f64], x: f64) -> usize {
    let i = values.partition_point(|&v| v < x);
    match (i.checked_sub(1), values.get(i)) {
        (Some(j), Some(&hi)) if (x - values[j]).abs() <= (hi - x).abs() => j,
        (Some(j), None) => j,
        _ => i,
    }
}

/// Σ min(p, q) of two histograms after normalising each to sum 1.
fn overlap(a: &[f64], b: &[f64]) -> f64 {
    let (sa, sb) = (a.iter().sum::<f64>(), b.iter().sum::<f64>());
    if sa <= 0.0 || sb <= 0.0 {
        return f64::NAN;
    }
    a.iter().zip(b).map(|(x, y)| (x / sa).min(y / sb)).sum()
}

/// The real frames of one sequence and the simulated frames at the same places.
fn sequence_stats(
    ctx: &EvalContext,
    seq: &str,
    frames: usize,
) -> Result<Option<(Stats, Stats, usize)>> {
    let real_dir = ctx.data(&format!("kitti/sequences/{seq}"));
    let config = match ctx.semi_kitti_config(seq, Some(frames))? {
        Some(config) if real_dir.join("velodyne").is_dir() => config,
        _ => {
            eprintln!("sim: real KITTI {seq} or its pole map is absent, skipping it");
            return Ok(None);
        }
    };
    let drive = SemiKittiDrive::new(&config, SEED)?;
    let mut elevations = drive.lidar().elevations_rad.clone();
    elevations.sort_by(f64::total_cmp);
    let firings = drive.lidar().azimuths_rad.len();
    let (mut real, mut sim) = (Stats::new(elevations.len()), Stats::new(elevations.len()));
    let sequence = KittiSequence::open(&real_dir)?;
    for scan in sequence.scans().take(frames) {
        let scan = scan?;
        let labels: Option<Vec<u32>> = sequence
            .labels(scan.frame)?
            .map(|l| l.iter().map(|l| l.raw()).collect());
        real.add(&scan.points, labels.as_deref(), &elevations);
        let simulated = drive.sim_scan(scan.frame as usize)?.cloud;
        sim.add(&simulated, simulated.label.as_deref(), &elevations);
    }
    Ok(Some((real, sim, elevations.len() * firings)))
}

/// Runs the section: writes its tables into `md`, returns its JSON.
pub fn run(ctx: &EvalContext, md: &mut String) -> Result<Value> {
    let (sequences, frames): (&[&str], usize) = if ctx.quick {
        (&["00"], 3)
    } else {
        (&["00", "01", "04", "07"], 10)
    };
    let mut section = Section::new();
    for seq in sequences {
        let Some((mut real, mut sim, beams)) = sequence_stats(ctx, seq, frames)? else {
            continue;
        };
        section.add(seq, &mut real, &mut sim, beams);
    }
    section.write(frames, md)
}

/// The section's tables and JSON rows, filled one sequence at a time.
struct Section {
    table: Table,
    gaps: Table,
    rows: Vec<Value>,
}

impl Section {
    fn new() -> Self {
        let mut header: Vec<String> = [
            "sequence",
            "data",
            "returns / frame",
            "no-return share",
            "median range [m]",
            "90 % range [m]",
            "pole points / frame",
            "trunk points / frame",
        ]
        .map(String::from)
        .to_vec();
        header.extend(CLASSES.iter().map(|c| format!("mean I {}", c.1)));
        let gaps = Table::new([
            "sequence",
            "elevation histogram overlap",
            "range histogram overlap",
            "intensity histogram overlap",
            "returns sim / real",
            "pole points sim / real",
        ]);
        Self {
            table: Table::new(header),
            gaps,
            rows: Vec::new(),
        }
    }

    /// Adds one sequence: the statistics of its real frames and of the simulated frames at
    /// the same places, `beams` firings per frame.
    fn add(&mut self, seq: &str, real: &mut Stats, sim: &mut Stats, beams: usize) {
        for (name, s) in [("real", &mut *real), ("simulated", &mut *sim)] {
            let mut row = vec![
                seq.to_string(),
                name.to_owned(),
                fmt_num(s.per_frame(s.returns), 0),
                fmt_num(1.0 - s.per_frame(s.returns) / beams as f64, 3),
                fmt_num(s.quantile(0.5), 1),
                fmt_num(s.quantile(0.9), 1),
                fmt_num(s.per_frame(s.pole_points), 0),
                fmt_num(s.per_frame(s.trunk_points), 0),
            ];
            row.extend((0..CLASSES.len()).map(|k| fmt_num(s.class_mean(k), 3)));
            self.table.row(row);
        }
        let elevation_overlap = overlap(&real.elevation_hist, &sim.elevation_hist);
        let range_overlap = overlap(&real.range_hist, &sim.range_hist);
        let intensity_overlap = overlap(&real.intensity_hist, &sim.intensity_hist);
        let returns_ratio = sim.returns as f64 / real.returns.max(1) as f64;
        let pole_ratio = sim.pole_points as f64 / real.pole_points.max(1) as f64;
        self.gaps.row([
            seq.to_string(),
            fmt_num(elevation_overlap, 3),
            fmt_num(range_overlap, 3),
            fmt_num(intensity_overlap, 3),
            fmt_num(returns_ratio, 2),
            fmt_num(pole_ratio, 2),
        ]);
        let side = |s: &Stats| {
            json!({
                "frames": s.frames, "returns_per_frame": s.per_frame(s.returns),
                "pole_points_per_frame": s.per_frame(s.pole_points),
                "trunk_points_per_frame": s.per_frame(s.trunk_points),
                "points_per_nominal_ring": s.per_ring,
                "elevation_histogram_half_degree": s.elevation_hist, "range_histogram_1m": s.range_hist,
                "class_mean_intensity": CLASSES.iter().enumerate()
                    .map(|(k, c)| json!({"class": c.0, "name": c.1, "mean": s.class_mean(k)}))
                    .collect::<Vec<_>>(),
            })
        };
        self.rows.push(json!({
            "sequence": seq, "beams_per_frame": beams,
            "real": side(real), "simulated": side(sim),
            "elevation_overlap": elevation_overlap, "range_overlap": range_overlap,
            "intensity_overlap": intensity_overlap, "returns_ratio": returns_ratio,
            "pole_points_ratio": pole_ratio,
        }));
    }

    /// Writes the section (frames 0 to `frames` − 1 of each sequence) into `md` and returns
    /// its JSON; a skip note when no sequence was added.
    fn write(self, frames: usize, md: &mut String) -> Result<Value> {
        let Self { table, gaps, rows } = self;
        if rows.is_empty() {
            let _ = writeln!(
                md,
                "*Skipped: no real KITTI frames with pole maps in RAYPATH_DATA.*\n"
            );
            return Ok(json!({ "skipped": "no real KITTI frames" }));
        }
        let _ = writeln!(
            md,
            "Each **real** KITTI HDL-64E frame (`kitti/sequences/NN`, frames 0–{}) beside the frame \
             **simulated** by `raypath-sim` at the same index of the same drive (the semi-synthetic \
             KITTI world: the real trajectory of `kitti-poles/NN` and its real pole map, seed \
             {SEED}). The two trajectories differ by up to a metre (SemanticKITTI's poses vs the \
             KITTI ground truth) and the simulated street has generic buildings, trees and cars, so \
             only distributions are compared. Elevations in 0.5° bins as seen from the velodyne \
             origin (the JSON also has counts per nearest nominal ring); no-return share against \
             64 × {} firings; intensities are KITTI's reflectance in [0, 1] and the \
             simulator's.\n",
            frames - 1,
            beams_hint(&rows),
        );
        md.push_str(&table.to_markdown()?);
        let _ = writeln!(
            md,
            "\nHow far the simulation is from the real frames (1 = identical distributions):\n"
        );
        md.push_str(&gaps.to_markdown()?);
        md.push('\n');
        Ok(json!({ "sequences": rows }))
    }
}

fn beams_hint(rows: &[Value]) -> u64 {
    rows.first()
        .and_then(|r| r["beams_per_frame"].as_u64())
        .map_or(0, |b| b / 64)
}

/// How far the simulator is from real scans, as one paragraph for the reports whose rows are
/// simulated: real KITTI 00 frames 0–2 beside the same frames simulated, measured in this
/// run (the full comparison is the realism section of `eval sim`). Says so when the real
/// frames are absent.
pub fn gap_note(ctx: &EvalContext) -> Result<String> {
    const FRAMES: usize = 3;
    let Some((mut real, mut sim, beams)) = sequence_stats(ctx, "00", FRAMES)? else {
        return Ok(
            "**Simulated scans.** How far they are from real scans is not measured in \
                   this run: the real KITTI frames (`kitti/sequences/00`) or the pole map \
                   (`kitti-poles/00`) are absent.\n"
                .to_owned(),
        );
    };
    Ok(gap_text(&mut real, &mut sim, beams, FRAMES))
}

/// The paragraph of [`gap_note`] from the statistics of real frames 0 to `frames` − 1 and of
/// the simulated frames at the same places, `beams` firings per frame.
fn gap_text(real: &mut Stats, sim: &mut Stats, beams: usize, frames: usize) -> String {
    let class = |s: &Stats, name: &str| {
        CLASSES
            .iter()
            .position(|c| c.1 == name)
            .map_or(f64::NAN, |k| s.class_mean(k))
    };
    let no_return = |s: &Stats| 1.0 - s.per_frame(s.returns) / beams as f64;
    format!(
        "**Simulated scans, not real ones.** How far `raypath-sim` is from real scans, \
         measured in this run on real KITTI 00 frames 0–{last} beside the same frames \
         simulated (the realism section of `eval sim` has the full comparison): {returns:.2}× \
         the real returns per frame, no-return share {nr_sim:.2} (real {nr_real:.2}), 90 % of \
         ranges within {q_sim:.0} m (real {q_real:.0} m), mean intensity on road {road_sim:.2} \
         (real {road_real:.2}) and vegetation {veg_sim:.2} (real {veg_real:.2}), {poles:.1}× \
         the real pole points; histogram overlap (1 = identical) of elevations {elev:.2}, \
         ranges {range:.2}, intensities {int:.2}. Simulated rows show a method on cleaner, \
         shorter-range scans than real ones; they are not real-data results.\n",
        last = frames - 1,
        returns = sim.returns as f64 / real.returns.max(1) as f64,
        nr_sim = no_return(sim),
        nr_real = no_return(real),
        q_sim = sim.quantile(0.9),
        q_real = real.quantile(0.9),
        road_sim = class(sim, "road"),
        road_real = class(real, "road"),
        veg_sim = class(sim, "vegetation"),
        veg_real = class(real, "vegetation"),
        poles = sim.pole_points as f64 / real.pole_points.max(1) as f64,
        elev = overlap(&real.elevation_hist, &sim.elevation_hist),
        range = overlap(&real.range_hist, &sim.range_hist),
        int = overlap(&real.intensity_hist, &sim.intensity_hist),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two frames of 50 real returns each: ranges 1–10 m, two elevation bins, road intensity
    /// 0.5, 10 pole and 4 trunk points.
    fn real() -> Stats {
        let mut s = Stats::new(2);
        s.frames = 2;
        s.returns = 100;
        s.ranges = (1..=10).map(f64::from).collect();
        s.elevation_hist[0] = 1.0;
        s.elevation_hist[1] = 1.0;
        s.range_hist[3] = 10.0;
        s.intensity_hist[10] = 4.0;
        s.class_intensity[0] = (1.5, 3);
        s.pole_points = 10;
        s.trunk_points = 4;
        s
    }

    /// Two frames of 30 simulated returns each: ranges 2–20 m, one elevation bin, no
    /// intensities in the histogram, road 0.25, vegetation 0.3, 6 pole points.
    fn simulated() -> Stats {
        let mut s = Stats::new(2);
        s.frames = 2;
        s.returns = 60;
        s.ranges = (1..=10).map(|i| f64::from(2 * i)).collect();
        s.elevation_hist[0] = 1.0;
        s.range_hist[3] = 5.0;
        s.class_intensity[0] = (1.0, 4);
        s.class_intensity[2] = (0.3, 1);
        s.pole_points = 6;
        s
    }

    fn cells(line: &str) -> Vec<&str> {
        line.split('|').map(str::trim).collect()
    }

    #[test]
    fn nearest_and_overlap() {
        assert_eq!(nearest(&[-1.0, 0.0, 2.0], 0.9), 1);
        assert_eq!(nearest(&[-1.0, 0.0, 2.0], 1.1), 2);
        assert_eq!(nearest(&[-1.0, 0.0, 2.0], -5.0), 0);
        assert_eq!(nearest(&[-1.0, 0.0, 2.0], 5.0), 2);
        assert_eq!(overlap(&[1.0, 1.0], &[2.0, 0.0]), 0.5);
        assert!(overlap(&[1.0], &[0.0]).is_nan());
    }

    /// One sequence of known statistics: the real and the simulated row, the gaps and the
    /// JSON.
    #[test]
    fn section_from_known_statistics() {
        let mut section = Section::new();
        section.add("00", &mut real(), &mut simulated(), 256);
        let mut md = String::from("before\n");
        let json = section.write(10, &mut md).unwrap();

        assert!(
            md.starts_with("before\nEach **real** KITTI HDL-64E frame"),
            "{md}"
        );
        assert!(md.contains("frames 0–9) beside the frame"), "{md}");
        assert!(md.contains("seed 2020)"), "{md}");
        assert!(md.contains("against 64 × 4 firings"), "{md}");
        let line = |start: &str| md.lines().find(|l| l.starts_with(start)).unwrap();
        assert_eq!(
            &cells(line("| 00       | real "))[1..14],
            [
                "00", "real", "50", "0.805", "6.0", "9.0", "5", "2", "0.500", "—", "—", "—", "—"
            ]
        );
        assert_eq!(
            &cells(line("| 00       | simulated "))[1..14],
            [
                "00",
                "simulated",
                "30",
                "0.883",
                "12.0",
                "18.0",
                "3",
                "0",
                "0.250",
                "—",
                "0.300",
                "—",
                "—"
            ]
        );
        assert!(md.contains("\nHow far the simulation is from the real frames"));
        let gaps = md.split("identical distributions):").nth(1).unwrap();
        let gap = gaps.lines().find(|l| l.starts_with("| 00 ")).unwrap();
        assert_eq!(
            &cells(gap)[1..7],
            ["00", "0.500", "1.000", "—", "0.60", "0.60"]
        );
        assert!(md.ends_with("|\n\n"), "{md:?}");

        let row = &json["sequences"][0];
        assert_eq!(row["sequence"], "00");
        assert_eq!(row["beams_per_frame"], 256);
        assert_eq!(row["elevation_overlap"], 0.5);
        assert_eq!(row["range_overlap"], 1.0);
        assert!(row["intensity_overlap"].is_null(), "NaN is written as null");
        assert_eq!(row["returns_ratio"], 0.6);
        assert_eq!(row["pole_points_ratio"], 0.6);
        assert_eq!(row["real"]["returns_per_frame"], 50.0);
        assert_eq!(row["real"]["trunk_points_per_frame"], 2.0);
        assert_eq!(row["simulated"]["class_mean_intensity"][0]["name"], "road");
        assert_eq!(row["simulated"]["class_mean_intensity"][0]["class"], 40);
        assert_eq!(row["simulated"]["class_mean_intensity"][0]["mean"], 0.25);
        assert_eq!(row["simulated"]["elevation_histogram_half_degree"][0], 1.0);
    }

    #[test]
    fn section_without_sequences_is_skipped() {
        let mut md = String::new();
        let json = Section::new().write(3, &mut md).unwrap();
        assert_eq!(
            md,
            "*Skipped: no real KITTI frames with pole maps in RAYPATH_DATA.*\n\n"
        );
        assert_eq!(json["skipped"], "no real KITTI frames");
    }

    /// The one-paragraph note of other reports, from the same known statistics.
    #[test]
    fn gap_text_from_known_statistics() {
        let text = gap_text(&mut real(), &mut simulated(), 256, 3);
        assert!(
            text.starts_with("**Simulated scans, not real ones.**"),
            "{text}"
        );
        for fragment in [
            "real KITTI 00 frames 0–2 beside",
            "0.60× the real returns per frame",
            "no-return share 0.88 (real 0.80)",
            "90 % of ranges within 18 m (real 9 m)",
            "mean intensity on road 0.25 (real 0.50)",
            "vegetation 0.30 (real NaN)",
            "0.6× the real pole points",
            "of elevations 0.50, ranges 1.00, intensities NaN.",
        ] {
            assert!(text.contains(fragment), "{fragment:?} in {text}");
        }
    }
}
