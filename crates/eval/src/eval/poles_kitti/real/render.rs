//! The markdown of the real section.

use std::fmt::Write;

use anyhow::Result;
use raypath_poles::{DetectionQuality, ReferenceRule};

use super::tally::{MARGIN_M, MATCH_M, RADIUS_M, Scored, Tally};
use super::{FRAMES, SequenceResult, Variant, diagnose};
use crate::table::{Table, fmt_num};

/// The ten-scan and the single-scan scorings of `variant`, summed over the sequences.
pub(super) fn pooled(results: &[SequenceResult], variant: Variant) -> (Scored, Scored) {
    let (mut full, mut single) = (Scored::default(), Scored::default());
    for e in results.iter().filter_map(|r| r.get(variant)) {
        full.merge(&e.full);
        single.merge(&e.single);
    }
    (full, single)
}

/// Columns of [`quality_cells`].
const QUALITY_HEADERS: [&str; 14] = [
    "data",
    "scans per map",
    "maps",
    "detections",
    "pole refs",
    "pole precision",
    "pole recall",
    "pole centre error [m]",
    "trunks found",
    "signs found",
    "pole+trunk precision",
    "pole+trunk recall",
    "all precision",
    "all recall",
];

/// The cells of one scoring.
fn quality_cells(data: &str, scans: &str, s: &Scored) -> Vec<String> {
    let q: Vec<DetectionQuality> = s.sets.iter().map(Tally::quality).collect();
    let rate = |v: f64, of: usize| {
        if of == 0 { "—".into() } else { fmt_num(v, 2) }
    };
    vec![
        data.to_string(),
        scans.to_string(),
        s.maps.to_string(),
        s.detections.to_string(),
        q[0].truth.to_string(),
        rate(q[0].precision, q[0].detected),
        rate(q[0].recall, q[0].truth),
        if q[0].matched == 0 {
            "—".into()
        } else {
            fmt_num(q[0].mean_centre_error_m, 3)
        },
        format!("{}/{}", q[1].matched, q[1].truth),
        format!("{}/{}", q[2].matched, q[2].truth),
        rate(q[3].precision, q[3].detected),
        rate(q[3].recall, q[3].truth),
        rate(q[4].precision, q[4].detected),
        rate(q[4].recall, q[4].truth),
    ]
}

/// Pole / trunk / sign references in the scoring region (the truths of the ten-scan map).
fn class_counts(s: &Scored) -> String {
    format!(
        "{} / {} / {}",
        s.sets[0].truth, s.sets[1].truth, s.sets[2].truth
    )
}

/// The markdown of the section.
pub(super) fn markdown(
    results: &[SequenceResult],
    rule: &ReferenceRule,
    notes: &[String],
) -> Result<String> {
    let mut pooled_table = Table::new(QUALITY_HEADERS);
    for variant in Variant::ALL {
        let (full, single) = pooled(results, variant);
        if full.maps > 0 {
            pooled_table.row(quality_cells(variant.label(), &FRAMES.to_string(), &full));
            pooled_table.row(quality_cells(variant.label(), "1", &single));
        }
    }
    let mut per_sequence = Table::new(["sequence"].into_iter().chain(QUALITY_HEADERS));
    let mut references = Table::new([
        "sequence",
        "real refs pole / trunk / sign",
        "real dropped",
        "poles.csv in region",
        "poles.csv ≤ 1 m of a real ref",
        "simulated refs pole / trunk / sign",
        "placed poles in region",
        "one-pose detections vs placed: precision / recall",
    ]);
    let mut misses = Table::new(diagnose::MISS_HEADERS);
    let mut false_positives = Table::new(diagnose::FALSE_POSITIVE_HEADERS);
    for r in results {
        for (variant, e) in &r.variants {
            let mut row = vec![r.sequence.to_string()];
            row.extend(quality_cells(variant.label(), &FRAMES.to_string(), &e.full));
            per_sequence.row(row);
            if matches!(variant, Variant::Real | Variant::RealFromOrigin) {
                for m in &e.misses {
                    misses.row(m.row(r.sequence, variant.label()));
                }
            }
            if *variant == Variant::Real {
                for f in &e.false_positives {
                    false_positives.row(f.row(r.sequence));
                }
            }
        }
        let real = r.get(Variant::Real);
        let sim = r.get(Variant::Simulated);
        let all = |s: &Scored| s.sets[4].quality();
        references.row([
            r.sequence.to_string(),
            real.map_or("—".into(), |e| class_counts(&e.full)),
            real.map_or("—".into(), |e| e.dropped.to_string()),
            r.csv.map_or("—".into(), |c| c.0.to_string()),
            r.csv.map_or("—".into(), |c| c.1.to_string()),
            sim.map_or("—".into(), |e| class_counts(&e.full)),
            r.placed.as_ref().map_or("—".into(), |p| p.0.to_string()),
            r.placed.as_ref().map_or("—".into(), |p| {
                format!(
                    "{} / {}",
                    fmt_num(all(&p.1).precision, 2),
                    fmt_num(all(&p.1).recall, 2)
                )
            }),
        ]);
    }
    let mut md = String::new();
    writeln!(md, "{}", intro(rule))?;
    writeln!(
        md,
        "### Real versus simulated, all sequences pooled\n\n{}",
        pooled_table.to_markdown()?
    )?;
    writeln!(md, "{CHANGE}")?;
    writeln!(
        md,
        "### Per sequence, ten-scan local map\n\n{}",
        per_sequence.to_markdown()?
    )?;
    writeln!(
        md,
        "### References\n\nIn the scoring region of the ten-scan map (the simulated region \
         follows the kitti-poles trajectory). `poles.csv ≤ 1 m of a real ref` = entries of \
         the real pole map of `kitti-poles/NN` (derived from SemanticKITTI over the whole \
         sequence, in the frame of the KITTI ground truth) matched to a reference clustered \
         here; the last column scores the one-pose simulation against the poles placed in \
         its world (kinds: trunk = trunk, others = pole).\n\n{}",
        references.to_markdown()?
    )?;
    writeln!(
        md,
        "### Missed real references (ten-scan local map)\n\nNearest scan range, labelled \
         shaft points in the band, their vertical span, sign-plate points, nearest \
         detection, and the labelled classes of all points within 0.3 m of the centre.\n\n{}",
        misses.to_markdown()?
    )?;
    writeln!(
        md,
        "### Real detections matched to no reference (ten-scan local map)\n\n{}",
        false_positives.to_markdown()?
    )?;
    for note in notes {
        writeln!(md, "* {note}")?;
    }
    Ok(md)
}

/// One sentence: real against one-pose simulated detection in the same ten-scan local maps.
pub(super) fn realism(results: &[SequenceResult]) -> String {
    let (real, _) = pooled(results, Variant::Real);
    let (sim, _) = pooled(results, Variant::Simulated);
    if real.maps == 0 || sim.maps == 0 {
        return "No real frames were available to compare the simulation with.".into();
    }
    let q = |s: &Scored, k: usize| s.sets[k].quality();
    format!(
        "How far these simulated scans are from real ones: in the ten-scan local maps of the \
         first ten frames of the real sequences (section above), the extractor finds {:.0} % \
         of the real SemanticKITTI poles at {:.0} % precision ({:.0} % / {:.0} % of all \
         pole-like objects), and {:.0} % at {:.0} % ({:.0} % / {:.0} %) in the same local maps \
         simulated.",
        100.0 * q(&real, 0).recall,
        100.0 * q(&real, 0).precision,
        100.0 * q(&real, 4).recall,
        100.0 * q(&real, 4).precision,
        100.0 * q(&sim, 0).recall,
        100.0 * q(&sim, 0).precision,
        100.0 * q(&sim, 4).recall,
        100.0 * q(&sim, 4).precision,
    )
}

/// What the section is and how it is scored.
fn intro(rule: &ReferenceRule) -> String {
    format!(
        "## Real KITTI scans against SemanticKITTI poles, beside the same local map simulated\n\n\
         **Real** rows: the real HDL-64E frames 0–9 of KITTI odometry sequences 00, 01, 04 and \
         07 (`kitti/sequences/NN`, SuMa poses of SemanticKITTI through the calibration's `Tr`), \
         extracted with `PoleParams::kitti()` in one local map of all ten scans centred at the \
         scan in the middle of their arc length (`scans per map` 10), and in ten single-scan \
         local maps (`scans per map` 1, pooled). **Simulated** rows: `raypath-sim` HDL-64E \
         scans at the first ten poses of the `kitti-poles/NN` ground-truth trajectory in the \
         street world built around the real pole map (world seed 2020), extracted and scored \
         the same way against references clustered from the simulated labels: `one-pose \
         scans` fire every beam of a scan from one pose (as the semi-synthetic drives below), \
         `sweeps` fire them from the sensor moving over the sweep and de-skew the points, as \
         KITTI's sweeps. The two trajectories differ (SuMa vs KITTI ground truth: 6.7 vs \
         7.7 m over frames 0–9 of 00), so the maps are alike, not identical: compare the \
         rates.\n\n\
         References (SemanticKITTI gives these classes no instance ids): the labelled points \
         of all ten scans inside the grid's height band, pole (80) and traffic-sign (81) \
         points together and trunk (71) points apart, linked in the ground plane at ≤ {} m \
         (connected components); a component is a **pole** when it has ≥ {} pole points \
         spanning ≥ {} m vertically (a sign plate on a post joins the post's pole), else a \
         **traffic sign** when it has ≥ {} sign points; a trunk component is a **trunk** \
         under the pole rule; the centre is the mean of the shaft points. Scored within \
         {RADIUS_M} m of a scan position and {MARGIN_M} m inside the grid footprint; a match \
         is the closest unused pair within {MATCH_M} m, jointly over all classes. Per class, \
         detections matched to another class are left out (`precision = matched / \
         (detections − matched to other classes)`); `trunks found` and `signs found` = \
         matched / references; `all` = any pole-like class (`precision = matched / \
         detections`). The headline is class pole (80) in the ten-scan map.\n",
        rule.link_m, rule.min_points, rule.min_extent_m, rule.min_points
    )
}

/// What was changed because of the real rows.
const CHANGE: &str = "\
**What changed because of the real rows.** Before, the extractor traced every ray from the \
scan's origin (rows `rays from the scan origin (before)`), and real recall was far below \
simulated recall. The missed poles showed why: rays of a real frame crossed the voxels of \
thin poles and ended on the ground and facades behind them — over frames 1, 4 and 7 of \
sequences 00 and 04, 878 rays passed within 3 cm of a labelled pole or trunk axis and ended \
behind it. KITTI's sweeps are de-skewed: every point is in the frame of the moment the \
sensor faced forward, but its beam was fired up to half a revolution earlier or later, from \
up to 0.35 m away at 25 km/h, so a ray drawn from the frame's origin runs beside the true one \
and carves free space through poles it never passed. The extractor now traces each ray from \
where the sensor was when it fired it (`SweepMotion`, `SweepTiming::kitti()`: clockwise, cut \
at the back, de-skewed to facing forward — of the cuts (every 15°), senses and reference \
times tried, the one that leaves the fewest see-through rays, 151 of the 878; constant \
velocity from the \
neighbouring poses); the KITTI preset's parameters are unchanged. The simulator gained the \
same sweeps (`Lidar3::scan_moving`, rows `simulated sweeps`): traced from the scan origin \
they lose a few poles too, but far fewer than the real frames, whose thin poles score \
closer to the threshold to begin with (their hits scatter over neighbouring voxels: the \
lasers of a real frame disagree on a pole's position by 2–5 cm, while a simulated pole \
fills one clean voxel column); traced from the moving origins they match the one-pose \
scans. The semi-synthetic drives below keep one-pose scans \
and origin rays, so their figures do not change. The real poles still missed are sign posts \
1.0–1.2 m high whose plate covers their upper half (the simulator places sign posts 2–3 m \
high) and, in single scans, trunks in undergrowth; the new false poles are 0.6 m wide \
posts labelled other-object that the origin rays used to carve away. Tried and not kept: \
no misses in the last 0.1 m before each endpoint, and μ_o = 0.1–0.15 (more single-scan \
recall, more false poles, no gain in the ten-scan maps once the origins are right).\n";

/// The real half of the results page's headline (`None` without real frames).
pub(super) fn headline(results: &[SequenceResult]) -> Option<String> {
    let (real, _) = pooled(results, Variant::Real);
    let (sim, _) = pooled(results, Variant::Simulated);
    if real.maps == 0 {
        return None;
    }
    let q = |s: &Scored| s.sets[0].quality();
    let sequences: Vec<&str> = results.iter().map(|r| r.sequence).collect();
    let simulated = if sim.maps == 0 {
        String::new()
    } else {
        format!(
            " (the same maps simulated: {:.0} % / {:.0} %)",
            100.0 * q(&sim).recall,
            100.0 * q(&sim).precision
        )
    };
    Some(format!(
        "Real KITTI {} (frames 0–9, ten-scan local maps, SemanticKITTI poles): recall {:.0} %, \
         precision {:.0} %, centre error {:.3} m{simulated}",
        sequences.join(", "),
        100.0 * q(&real).recall,
        100.0 * q(&real).precision,
        q(&real).mean_centre_error_m,
    ))
}
