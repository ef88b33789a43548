//! Where the SegComp Perceptron files lie under `$RAYPATH_DATA/segcomp/`: the layout of
//! `datasets/manifest.json` (`perceptron/{train,test}/perc.<split>.N[.Z]`) and the flat one
//! (`perc.<split>.N[.Z]` at the top), each range image with its `.gt-seg` and `.gt-ang`
//! beside it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use raypath_io::segcomp::{read_gt_ang, read_gt_seg, read_perceptron};
use raypath_sim::segcomp::Split;

use super::protocol::Image;

/// Compression suffixes the readers undo.
const SUFFIXES: [&str; 4] = ["", ".Z", ".gz", ".bz2"];

/// One scan on disk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScanFiles {
    /// `N` of `perc.<split>.N`.
    pub number: u32,
    /// The range image.
    pub range: PathBuf,
    /// The ground-truth segmentation, when present.
    pub gt_seg: Option<PathBuf>,
    /// The ground-truth angles, when present.
    pub gt_ang: Option<PathBuf>,
}

/// The name without its compression suffix.
fn stem(name: &str) -> &str {
    name.strip_suffix(".Z")
        .or_else(|| name.strip_suffix(".gz"))
        .or_else(|| name.strip_suffix(".bz2"))
        .unwrap_or(name)
}

/// `N` when `name` is `perc.<split>.N` with an optional compression suffix.
fn scan_number(name: &str, split: Split) -> Option<u32> {
    let digits = stem(name).strip_prefix(&format!("perc.{}.", split.name()))?;
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The companion `<stem>.<ext>` of `range` with any compression suffix.
fn companion(range: &Path, ext: &str) -> Option<PathBuf> {
    let name = range.file_name()?.to_str()?;
    SUFFIXES
        .iter()
        .map(|s| range.with_file_name(format!("{}.{ext}{s}", stem(name))))
        .find(|p| p.is_file())
}

/// The range images of `split` under `root` (`$RAYPATH_DATA/segcomp`), by scan number: those
/// in `root/perceptron/<split>/` (the manifest's layout) and those at the top of `root`; a
/// number found in both is taken from the manifest's layout.
pub fn find(root: &Path, split: Split) -> Vec<ScanFiles> {
    let mut found: BTreeMap<u32, PathBuf> = BTreeMap::new();
    let dirs = [
        root.to_path_buf(),
        root.join("perceptron").join(split.name()),
    ];
    for dir in dirs {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file())
            .collect();
        // Plain before compressed when both copies lie side by side.
        files.sort_by_key(|p| (p.file_name().map(|n| n.len()), p.clone()));
        let mut here: BTreeMap<u32, PathBuf> = BTreeMap::new();
        for path in files {
            let Some(number) = path
                .file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| scan_number(n, split))
            else {
                continue;
            };
            here.entry(number).or_insert(path);
        }
        // The later directory (the manifest's layout) wins.
        found.extend(here);
    }
    found
        .into_iter()
        .map(|(number, range)| ScanFiles {
            number,
            gt_seg: companion(&range, "gt-seg"),
            gt_ang: companion(&range, "gt-ang"),
            range,
        })
        .collect()
}

/// Reads one scan: the cloud through the reader's Perceptron geometry, the labels and, when
/// present, the angles.
pub fn load(scan: &ScanFiles) -> Result<Image> {
    let perc = read_perceptron(&scan.range)
        .with_context(|| format!("reading {}", scan.range.display()))?;
    let gt_path = scan
        .gt_seg
        .as_ref()
        .with_context(|| format!("no .gt-seg beside {}", scan.range.display()))?;
    let gt = read_gt_seg(gt_path).with_context(|| format!("reading {}", gt_path.display()))?;
    anyhow::ensure!(
        gt.labels.len() == perc.cloud.len(),
        "{}: {} labels for {} pixels",
        gt_path.display(),
        gt.labels.len(),
        perc.cloud.len()
    );
    let angles = match &scan.gt_ang {
        Some(path) => Some(
            read_gt_ang(path)
                .with_context(|| format!("reading {}", path.display()))?
                .pairs
                .iter()
                .map(|p| (p.label_a, p.label_b, p.angle_deg))
                .collect(),
        ),
        None => None,
    };
    let name = scan
        .range
        .file_name()
        .and_then(|n| n.to_str())
        .map_or_else(|| scan.range.display().to_string(), |n| stem(n).to_owned());
    Ok(Image {
        name,
        cloud: perc.cloud,
        gt: gt.labels.into_iter().map(Some).collect(),
        angles,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn touch(path: &Path) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, b"x").unwrap();
    }

    #[test]
    fn segcomp_finds_the_manifest_layout_and_the_flat_one() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        // The manifest's layout, compressed, for both splits.
        for n in [0, 1, 10] {
            touch(&root.join(format!("perceptron/test/perc.test.{n}.Z")));
            touch(&root.join(format!("perceptron/test/perc.test.{n}.gt-seg.Z")));
        }
        touch(&root.join("perceptron/test/perc.test.0.gt-ang.Z"));
        touch(&root.join("perceptron/train/perc.train.3.Z"));
        touch(&root.join("perceptron/train/perc.train.3.gt-seg"));
        // The flat layout, plain; scan 1 also in the manifest's layout (that copy wins).
        for n in [1, 2, 9] {
            touch(&root.join(format!("perc.test.{n}")));
            touch(&root.join(format!("perc.test.{n}.gt-seg")));
        }
        touch(&root.join("perc.train.4.gz"));
        // Not scans.
        touch(&root.join("perc.test.x"));
        touch(&root.join("perc.test.5.gt-seg"));
        touch(&root.join("perceptron/test/perc.train.7"));
        touch(&root.join("abw.test.1"));

        let test = find(root, Split::Test);
        let numbers: Vec<u32> = test.iter().map(|s| s.number).collect();
        assert_eq!(numbers, [0, 1, 2, 9, 10]);
        let by = |n: u32| test.iter().find(|s| s.number == n).unwrap();
        assert_eq!(by(0).range, root.join("perceptron/test/perc.test.0.Z"));
        assert_eq!(
            by(0).gt_seg.as_deref(),
            Some(root.join("perceptron/test/perc.test.0.gt-seg.Z").as_path())
        );
        assert_eq!(
            by(0).gt_ang.as_deref(),
            Some(root.join("perceptron/test/perc.test.0.gt-ang.Z").as_path())
        );
        assert_eq!(by(1).range, root.join("perceptron/test/perc.test.1.Z"));
        assert_eq!(by(2).range, root.join("perc.test.2"));
        assert_eq!(
            by(2).gt_seg.as_deref(),
            Some(root.join("perc.test.2.gt-seg").as_path())
        );
        assert_eq!(by(2).gt_ang, None);
        assert_eq!(by(10).range, root.join("perceptron/test/perc.test.10.Z"));

        let train = find(root, Split::Train);
        let names: Vec<PathBuf> = train.iter().map(|s| s.range.clone()).collect();
        assert_eq!(
            names,
            [
                root.join("perceptron/train/perc.train.3.Z"),
                root.join("perc.train.4.gz")
            ]
        );
        assert!(train[0].gt_seg.is_some() && train[1].gt_seg.is_none());
        assert!(find(&root.join("absent"), Split::Test).is_empty());
    }

    #[test]
    fn segcomp_scan_numbers_need_digits() {
        assert_eq!(scan_number("perc.test.12.Z", Split::Test), Some(12));
        assert_eq!(scan_number("perc.test.12", Split::Test), Some(12));
        assert_eq!(scan_number("perc.train.0.bz2", Split::Train), Some(0));
        assert_eq!(scan_number("perc.test.12", Split::Train), None);
        assert_eq!(scan_number("perc.test.", Split::Test), None);
        assert_eq!(scan_number("perc.test.1.gt-seg", Split::Test), None);
    }
}
