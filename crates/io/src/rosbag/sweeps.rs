//! Sweep sequences from the `PointCloud2` topic of a bag, read on demand.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use raypath_geometry::{PointCloud, Pose3};

use super::bag::BagFiles;
use super::cloud::decode_cloud;
use super::poses::Poses;
use super::reader::{ChunkCache, Classify, McapReader};
use super::select::{CloudRef, POINT_CLOUD2, first_pass, message_error};
use crate::error::{Error, Result};
use crate::sequence::{SweepSequence, Topics};

/// Skipped clouds are listed one by one up to this many.
const MAX_SKIP_WARNINGS: usize = 5;

struct Rereader {
    files: Vec<PathBuf>,
    topic: String,
    refs: Vec<CloudRef>,
    state: Mutex<State>,
}

/// The open files, the last chunk decoded (and those decoded ahead), the last sweep read.
struct State {
    readers: Vec<Option<McapReader>>,
    cache: ChunkCache,
    last: Option<usize>,
}

impl Rereader {
    fn read(&self, index: usize) -> Result<PointCloud> {
        let r = self.refs.get(index).ok_or_else(|| Error::UnknownFormat {
            path: self.files[0].clone(),
            reason: format!("no sweep {index}"),
        })?;
        let file = self
            .files
            .get(r.loc.file as usize)
            .ok_or_else(|| Error::UnknownFormat {
                path: self.files[0].clone(),
                reason: format!("sweep {index}: no file {}", r.loc.file),
            })?;
        let data = {
            let mut guard = self.state.lock().map_err(|_| Error::UnknownFormat {
                path: file.clone(),
                reason: "an earlier read panicked".into(),
            })?;
            let state = &mut *guard;
            // Read in order: the next clouds' chunks are decoded ahead meanwhile.
            let in_order = state.last.is_none_or(|last| index == last + 1);
            state.last = Some(index);
            let slot = &mut state.readers[r.loc.file as usize];
            if slot.is_none() {
                let classify: Classify = Arc::new(|_| None);
                *slot = Some(McapReader::open(file, r.loc.file, classify)?);
            }
            match slot.as_mut() {
                Some(reader) => {
                    let data = reader.reread(r.loc, &mut state.cache)?;
                    if in_order {
                        let next = self.refs[index + 1..].iter().map(|r| r.loc);
                        reader.prefetch(next, &mut state.cache);
                    }
                    data
                }
                None => {
                    return Err(Error::UnknownFormat {
                        path: file.clone(),
                        reason: "the file cannot be opened again".into(),
                    });
                }
            }
        };
        // Decoded without the lock (and without copying the message out of its chunk).
        let (_, cloud) = decode_cloud(data.bytes())
            .map_err(|e| message_error(file, r.loc, &self.topic, r.log_time, e))?;
        Ok(cloud)
    }
}

/// Reads the stamps and poses of the clouds of the bag at `path`; the clouds are read on
/// demand by [`SweepSequence::sweep`] (see [`crate::rosbag`] for the choices made).
pub fn open_sweeps(path: &Path, topics: &Topics) -> Result<SweepSequence> {
    let bag = BagFiles::resolve(path)?;
    let mut pass = first_pass(&bag, true)?;
    for w in &pass.warnings {
        log::warn!("{w}");
    }
    let topic = pass
        .choose(
            path,
            POINT_CLOUD2,
            topics.cloud.as_deref(),
            "--cloud-topic",
            true,
        )?
        .ok_or_else(|| Error::UnknownFormat {
            path: path.to_path_buf(),
            reason: "no PointCloud2 topic".into(),
        })?;
    let mut refs = pass.clouds.remove(&topic).unwrap_or_default();
    let mut poses = Poses::new(path, &mut pass, topics)?;
    refs.sort_by_key(|r| r.stamp);
    let mut stamps = Vec::with_capacity(refs.len());
    let mut odometry: Vec<Option<Pose3>> = Vec::with_capacity(refs.len());
    let mut reference: Vec<Option<Pose3>> = Vec::with_capacity(refs.len());
    let mut kept = Vec::with_capacity(refs.len());
    let mut skipped = 0;
    let mut skip = |r: &CloudRef, reason: &str| {
        skipped += 1;
        if skipped <= MAX_SKIP_WARNINGS {
            log::warn!(
                "{}: {topic} at log time {:.9} s skipped: {reason}",
                path.display(),
                r.log_time as f64 * 1e-9
            );
        }
    };
    for r in refs {
        let t = r.stamp.secs();
        if stamps.last().is_some_and(|&last| t <= last) {
            skip(&r, "a cloud with the same header stamp came first");
            continue;
        }
        match poses.at(&r.frame_id, t) {
            Ok(p) => {
                odometry.push(p.world_from_robot.map(|w| w * p.robot_from_sensor));
                reference.push(p.reference);
            }
            Err(reason) => {
                skip(&r, &reason);
                continue;
            }
        }
        stamps.push(t);
        kept.push(r);
    }
    if skipped > MAX_SKIP_WARNINGS {
        log::warn!(
            "{}: {skipped} clouds of {topic} skipped in all",
            path.display()
        );
    }
    let odometry: Option<Vec<Pose3>> = odometry.into_iter().collect();
    let covered = reference.iter().filter(|p| p.is_some()).count();
    if covered > 0 && covered < reference.len() {
        log::warn!(
            "{}: the reference poses cover {covered} of {} clouds; they are not used",
            path.display(),
            reference.len()
        );
    }
    let reference: Option<Vec<Pose3>> = reference.into_iter().collect();
    let reader = Rereader {
        state: Mutex::new(State {
            readers: (0..bag.files.len()).map(|_| None).collect(),
            cache: ChunkCache::default(),
            last: None,
        }),
        files: bag.files,
        topic,
        refs: kept,
    };
    SweepSequence::from_reader(
        bag.path,
        crate::sequence::SweepFormat::Bag,
        stamps,
        reference,
        odometry,
        Box::new(move |i| reader.read(i)),
    )
}
