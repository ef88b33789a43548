//! Planar frames from the `LaserScan` topic of a bag.

mod decode;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use raypath_geometry::Pose3;

use super::bag::BagFiles;
use super::poses::Poses;
use super::reader::{ChannelInfo, Classify, McapReader};
use super::select::{LASER_SCAN, ROLE_SCAN, first_pass, is_ros2, message_error, normalize_type};
use crate::error::{Error, Result};
use crate::sequence::{Origin, PlanarFrame, PlanarSource, Topics};
use decode::{BATCH, Batch, Decoders};

/// Skipped scans are listed one by one up to this many.
const MAX_SKIP_WARNINGS: usize = 5;

/// The scans of one `sensor_msgs/msg/LaserScan` topic of a bag with their poses, streamed in
/// file order (a second pass after odometry and tf were read; the scans are decoded ahead on
/// other threads while the poses of earlier ones are computed).
pub struct BagScans {
    name: PathBuf,
    files: Vec<PathBuf>,
    next_file: usize,
    reader: Option<McapReader>,
    topic: Arc<str>,
    poses: Poses,
    known_warnings: HashSet<String>,
    warnings: Vec<String>,
    skipped: usize,
    failed: bool,
    decoders: Decoders,
    /// The batch whose frames are being handed out, and the next of them.
    current: Option<(Batch, usize)>,
    /// An error met while reading ahead: handed out after the scans before it.
    deferred: Option<Error>,
    /// Every file was read.
    exhausted: bool,
}

/// Reads the odometry, tf and reference poses of the bag at `path` and streams the scans of
/// its `LaserScan` topic (see [`crate::rosbag`] for how topics and frames are chosen).
pub fn open_planar(path: &Path, topics: &Topics) -> Result<Box<dyn PlanarSource>> {
    Ok(Box::new(BagScans::open(path, topics)?))
}

impl BagScans {
    /// Opens the bag (first pass over odometry, tf and reference poses).
    pub fn open(path: &Path, topics: &Topics) -> Result<Self> {
        let bag = BagFiles::resolve(path)?;
        let mut pass = first_pass(&bag, false)?;
        for w in &pass.warnings {
            log::warn!("{w}");
        }
        let topic = pass
            .choose(
                path,
                LASER_SCAN,
                topics.scan.as_deref(),
                "--scan-topic",
                true,
            )?
            .ok_or_else(|| Error::UnknownFormat {
                path: path.to_path_buf(),
                reason: "no LaserScan topic".into(),
            })?;
        let mut poses = Poses::new(path, &mut pass, topics)?;
        if !poses.has_motion() {
            let note = "the bag has no odometry and no tf: the robot and laser poses are the \
                        identity";
            log::warn!("{}: {note}", path.display());
            poses.notes.push(note.into());
        }
        Ok(Self {
            name: bag.path.clone(),
            files: bag.files,
            next_file: 0,
            reader: None,
            topic: Arc::from(topic.as_str()),
            poses,
            known_warnings: pass.warnings.iter().cloned().collect(),
            warnings: pass.warnings,
            skipped: 0,
            failed: false,
            decoders: Decoders::start(),
            current: None,
            deferred: None,
            exhausted: false,
        })
    }

    /// The topic read.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The warnings met so far (truncation, messages out of order, tf conflicts, skipped
    /// scans), also emitted through the `log` facade as they occur.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Scans skipped so far because odometry or tf did not cover their time.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    fn flush_warnings(&mut self) {
        if let Some(reader) = self.reader.as_mut() {
            for w in reader.take_warnings() {
                if self.known_warnings.insert(w.clone()) {
                    log::warn!("{w}");
                    self.warnings.push(w);
                }
            }
        }
    }

    fn open_next(&mut self) -> Result<bool> {
        let Some(file) = self.files.get(self.next_file) else {
            return Ok(false);
        };
        let topic = self.topic.clone();
        let classify: Classify = Arc::new(move |c: &ChannelInfo| {
            (is_ros2(c) && c.topic == *topic && normalize_type(&c.schema_name) == LASER_SCAN)
                .then_some(ROLE_SCAN)
        });
        self.reader = Some(McapReader::open(file, self.next_file as u32, classify)?);
        self.next_file += 1;
        Ok(true)
    }

    /// Reads scans ahead (raw) into batches for the decoders, until enough are ahead or the
    /// files end; an error is kept for after the scans before it.
    fn read_ahead(&mut self) {
        while self.deferred.is_none() && !self.exhausted && self.decoders.has_room() {
            let mut batch = self.decoders.batch();
            while batch.items.len() < BATCH {
                if self.reader.is_none() {
                    match self.open_next() {
                        Ok(true) => {}
                        Ok(false) => {
                            self.exhausted = true;
                            break;
                        }
                        Err(e) => {
                            self.deferred = Some(e);
                            break;
                        }
                    }
                }
                let Some(reader) = self.reader.as_mut() else {
                    break;
                };
                match reader.next_message() {
                    Ok(Some(m)) => batch.push(self.next_file - 1, m.log_time, m.loc, m.data),
                    Ok(None) => {
                        self.flush_warnings();
                        self.reader = None;
                    }
                    Err(e) => {
                        self.deferred = Some(e);
                        break;
                    }
                }
            }
            if batch.items.is_empty() {
                self.decoders.recycle(batch);
                break;
            }
            self.decoders.submit(batch);
        }
    }

    fn next_frame(&mut self) -> Result<Option<PlanarFrame>> {
        loop {
            let Some((batch, next)) = self.current.as_mut() else {
                self.read_ahead();
                let batch = self
                    .decoders
                    .next()
                    .map_err(|reason| Error::UnknownFormat {
                        path: self.name.clone(),
                        reason,
                    })?;
                match batch {
                    Some(batch) => self.current = Some((batch, 0)),
                    None => return self.end(),
                }
                continue;
            };
            let Some(item) = batch.items.get_mut(*next) else {
                if let Some((batch, _)) = self.current.take() {
                    self.decoders.recycle(batch);
                }
                continue;
            };
            *next += 1;
            let (log_time, loc, file) = (item.log_time, item.loc, item.file);
            let file = &self.files[file];
            let decoded = item.decoded.take().unwrap_or_else(|| {
                Err(super::cdr::CdrError {
                    offset: 0,
                    reason: "not decoded".into(),
                })
            });
            let (stamp, frame, scan) =
                decoded.map_err(|e| message_error(file, loc, &self.topic, log_time, e))?;
            let t = stamp.secs();
            let poses = match self.poses.at(batch.frame(&frame), t) {
                Ok(p) => p,
                Err(reason) => {
                    self.skipped += 1;
                    if self.skipped <= MAX_SKIP_WARNINGS {
                        let w = format!(
                            "{}: {} at log time {:.9} s skipped: {reason}",
                            file.display(),
                            self.topic,
                            log_time as f64 * 1e-9
                        );
                        log::warn!("{w}");
                        self.warnings.push(w);
                    }
                    continue;
                }
            };
            let world_from_robot = poses.world_from_robot.unwrap_or_else(Pose3::identity);
            return Ok(Some(PlanarFrame {
                stamp_secs: t,
                ipc_stamp_secs: None,
                scan,
                world_from_robot: world_from_robot.to_planar(),
                world_from_laser: (world_from_robot * poses.robot_from_sensor).to_planar(),
                reference: poses.reference.map(|p| p.to_planar()),
                origin: Origin::LogTimeNs(log_time),
            }));
        }
    }

    /// After the last scan: the error met reading ahead, if any, else the end.
    fn end(&mut self) -> Result<Option<PlanarFrame>> {
        if let Some(e) = self.deferred.take() {
            return Err(e);
        }
        if self.skipped > MAX_SKIP_WARNINGS {
            let w = format!(
                "{}: {} scans of {} skipped in all (odometry or tf do not cover their times)",
                self.name.display(),
                self.skipped,
                self.topic
            );
            log::warn!("{w}");
            self.warnings.push(w);
        }
        Ok(None)
    }
}

impl Iterator for BagScans {
    type Item = Result<PlanarFrame>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        match self.next_frame() {
            Ok(frame) => frame.map(Ok),
            Err(e) => {
                self.failed = true;
                Some(Err(e))
            }
        }
    }
}

impl PlanarSource for BagScans {
    fn name(&self) -> &Path {
        &self.name
    }

    fn warnings(&self) -> &[String] {
        &self.warnings
    }
}
