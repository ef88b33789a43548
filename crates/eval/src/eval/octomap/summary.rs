//! The summary of the earlier data sets (beam-based, r = 0.2 m, M = 8): leaf reduction,
//! insertion-time and bytes ratios for the thesis' fusion rule and the equal-value rule.

use anyhow::Result;
use serde_json::{Value, json};

use super::measure::{Compared, SetInfo};
use super::{EQUAL_BATCH_LABEL, EQUAL_LABEL, EQUAL_UPDATED_BATCH_LABEL, EQUAL_UPDATED_LABEL};
use crate::eval::comparable;
use crate::table::{Table, fmt_num};

/// The data sets summed in the summary: the summary keys keep their meaning.
const IN_SUMS: [&str; 3] = ["scan.dat", "scan.dat-x5", "urban"];

/// Sums for one fusion rule over the summary's data sets, geb079 beside them.
#[derive(Default)]
pub struct Sums {
    ours_insert: f64,
    peer_insert: f64,
    ours_bytes: usize,
    peer_bytes: usize,
    /// The leaf reduction of the urban drive (else of the first set summed) and its name.
    pub reduction: Option<(String, f64)>,
    /// geb079: leaf reduction, insertion ratio, bytes ratio.
    geb079: Option<(f64, f64, f64)>,
}

impl Sums {
    /// Adds one run of data set `set` (nothing without OctoMap).
    fn add(&mut self, set: &str, c: &Compared) {
        let (Some(p), Some(red), Some(ins), Some(b)) =
            (&c.peer, c.reduction(), c.insert_ratio(), c.bytes_ratio())
        else {
            return;
        };
        if set == "geb079" {
            self.geb079 = Some((red, ins, b));
        } else if IN_SUMS.contains(&set) {
            self.ours_insert += c.ours.insert_secs;
            self.peer_insert += p.insert_secs;
            self.ours_bytes += c.ours.bytes;
            self.peer_bytes += p.memory_bytes;
            if self.reduction.is_none() || set == "urban" {
                self.reduction = Some((set.to_owned(), red));
            }
        }
    }

    fn insertion_ratio(&self) -> Option<f64> {
        (self.peer_insert > 0.0).then(|| self.ours_insert / self.peer_insert)
    }

    fn bytes_ratio(&self) -> Option<f64> {
        (self.peer_bytes > 0).then(|| self.ours_bytes as f64 / self.peer_bytes as f64)
    }

    fn json(&self) -> Value {
        json!({
            "leaf_reduction_vs_pruned_octomap_0_2m": self.reduction.as_ref().map(|r| r.1),
            "leaf_reduction_data": self.reduction.as_ref().map(|r| r.0.clone()),
            "insertion_time_ratio_vs_octomap": self.insertion_ratio(),
            "bytes_ratio_vs_octomap": self.bytes_ratio(),
            "geb079": self.geb079.map(|(red, ins, b)| json!({
                "leaf_reduction_vs_pruned_octomap_0_2m": red,
                "insertion_time_ratio_vs_octomap": ins,
                "bytes_ratio_vs_octomap": b,
            })),
        })
    }
}

/// The summary: the thesis' rule and the four equal-value variants.
pub struct Summary {
    /// The thesis' rule (the runs at r = 0.2 m, M = 8, beam-based).
    pub thesis: Sums,
    /// The equal-value rule: beam samples, every updated cell, beam samples fused every 10
    /// scans, every updated cell fused every 10 scans.
    equal: [Sums; 4],
}

impl Summary {
    /// Sums over the data sets' runs and variants.
    pub fn of(sets: &[&SetInfo]) -> Self {
        let mut summary = Self {
            thesis: Sums::default(),
            equal: Default::default(),
        };
        for set in sets {
            for run in set.runs.iter().filter(|r| r.at_02()) {
                summary.thesis.add(&set.name, &run.compared);
            }
            for variant in &set.variants {
                let labels = [
                    EQUAL_LABEL,
                    EQUAL_UPDATED_LABEL,
                    EQUAL_BATCH_LABEL,
                    EQUAL_UPDATED_BATCH_LABEL,
                ];
                if let Some(k) = labels.iter().position(|l| *l == variant.label) {
                    summary.equal[k].add(&set.name, &variant.compared);
                }
            }
        }
        summary
    }

    /// `summary` of the JSON: the thesis rule's keys, the equal-value rule's, `real`.
    pub fn json(&self, octomap_available: bool, real_rows: &[Value]) -> Value {
        let mut json = self.thesis.json();
        json["octomap_available"] = json!(octomap_available);
        json["equal_value"] = self.equal[0].json();
        json["equal_value_updated_cells"] = self.equal[1].json();
        json["equal_value_every_10_scans"] = self.equal[2].json();
        json["equal_value_updated_cells_every_10_scans"] = self.equal[3].json();
        json["real"] = json!(real_rows);
        json
    }

    /// The summary table.
    pub fn table(&self) -> Result<String> {
        let mut table = Table::new(["quantity", "measured", "thesis / aim", comparable::HEADER]);
        for row in self.thesis_rows() {
            table.row(row);
        }
        for (sums, label) in self.equal.iter().zip([
            "beam samples",
            "every updated cell",
            "beam samples, fused every 10 scans",
            "every updated cell, fused every 10 scans",
        ]) {
            table.row(equal_row(sums, label));
        }
        table.to_markdown()
    }

    /// The thesis rule's rows: leaf reduction, insertion and bytes ratios, geb079.
    fn thesis_rows(&self) -> Vec<[String; 4]> {
        let t = &self.thesis;
        let mut rows = vec![
            [
                format!(
                    "leaf reduction vs pruned OctoMap ({})",
                    t.reduction.as_ref().map_or("—", |r| r.0.as_str())
                ),
                t.reduction
                    .as_ref()
                    .map_or("—".into(), |r| format!("{:.2} %", 100.0 * r.1)),
                "28.51 % fewer leaves at 0.2 m (Freiburg campus, Fig. 2.9b); aim ≥ 28.5 %".into(),
                comparable::no(&format!(
                    "{}; thesis: the real 81-scan Freiburg campus graph (not available here)",
                    summary_data(t.reduction.as_ref().map(|r| r.0.as_str()))
                )),
            ],
            [
                "insertion time ours / OctoMap (scan.dat, scan.dat-x5, urban)".to_owned(),
                t.insertion_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
                "thesis: Rtree slower (> 1, Fig. 2.9c); aim ≤ 1".into(),
                comparable::no(
                    "real OctoMap sample scan and simulated urban drive, ratio of one run on \
                     shared cores; thesis: the real Freiburg campus graph on one Intel i5-2500K \
                     core",
                ),
            ],
            [
                "bytes ours / OctoMap memoryUsage() (scan.dat, scan.dat-x5, urban)".to_owned(),
                t.bytes_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
                "thesis: not reported; aim < 1".into(),
                comparable::no("the thesis reports no memory figure: the aim only"),
            ],
        ];
        if let Some((red, ins, b)) = t.geb079 {
            rows.push([
                "geb079 (not in the rows above): leaf reduction / insertion ratio / bytes ratio"
                    .to_owned(),
                format!(
                    "{:.2} % / {} / {}",
                    100.0 * red,
                    fmt_num(ins, 2),
                    fmt_num(b, 2)
                ),
                "thesis: 28.51 % / > 1 / —; aim ≥ 28.5 % / ≤ 1 / < 1".into(),
                comparable::no(
                    "scans simulated in the real geb079 building map; thesis: the real Freiburg \
                     campus graph",
                ),
            ]);
        }
        rows
    }
}

/// The row of one equal-value variant (`label`: its selection).
fn equal_row(sums: &Sums, label: &str) -> [String; 4] {
    [
        format!(
            "equal-value rule (ours, {label}): leaf reduction ({}) / insertion ratio / bytes ratio",
            sums.reduction.as_ref().map_or("—", |r| r.0.as_str())
        ),
        format!(
            "{} / {} / {}",
            sums.reduction
                .as_ref()
                .map_or("—".into(), |r| format!("{:.2} %", 100.0 * r.1)),
            sums.insertion_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
            sums.bytes_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
        ),
        "not in the thesis (our extension); aim ≥ 28.5 % / ≤ 1 / < 1".into(),
        comparable::no("not in the thesis (our extension): the aim only"),
    ]
}

/// What the data of the summary's leaf-reduction row are (`set`: its name), for the
/// "comparable" cell.
fn summary_data(set: Option<&str>) -> String {
    match set {
        Some("urban") => "simulated HDL-64E urban drive, OctoMap in the same run".to_owned(),
        Some(name) => format!("`{name}`, OctoMap in the same run"),
        None => "no data set in this run".to_owned(),
    }
}
