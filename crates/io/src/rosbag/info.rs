//! What a bag holds: topics, types, counts, rates and time span (`raypath info bag.mcap`).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
use serde::Serialize;

use super::bag::BagFiles;
use super::reader::{ChannelInfo, ChannelStats, McapReader};
use super::select::normalize_type;
use crate::error::{Error, Location, Result};

/// One topic of a bag.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TopicInfo {
    /// Topic name.
    pub name: String,
    /// Message type (`sensor_msgs/msg/LaserScan`).
    #[serde(rename = "type")]
    pub type_name: String,
    /// Message encoding (`cdr`).
    pub message_encoding: String,
    /// Number of messages.
    pub message_count: u64,
    /// Log time of the first message, seconds.
    pub first_secs: Option<f64>,
    /// Log time of the last message, seconds.
    pub last_secs: Option<f64>,
    /// Mean message rate over the topic's span, Hz (`(count − 1) / span`).
    pub rate_hz: Option<f64>,
}

/// What a rosbag2 recording holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BagInfo {
    /// The bag directory or `.mcap` file.
    pub path: PathBuf,
    /// Its MCAP files.
    pub files: Vec<PathBuf>,
    /// Total size of the files, bytes.
    pub file_size_bytes: u64,
    /// Storage format (`mcap`).
    pub storage: String,
    /// The MCAP profile (`ros2`; `ros1` for ROS 1 recordings).
    pub profile: String,
    /// Chunk compressions (`zstd`, `lz4`, `none`).
    pub compression: Vec<String>,
    /// True when every file has a summary with message statistics (read from it rather than
    /// by a scan of the whole file).
    pub indexed: bool,
    /// Number of messages.
    pub message_count: u64,
    /// Log time of the first message, seconds.
    pub start_secs: Option<f64>,
    /// Log time of the last message, seconds.
    pub end_secs: Option<f64>,
    /// `end − start`, seconds.
    pub duration_secs: f64,
    /// The topics by name.
    pub topics: Vec<TopicInfo>,
    /// Problems found (truncation, missing summary).
    pub warnings: Vec<String>,
}

struct FileInfo {
    profile: String,
    channels: Vec<(ChannelInfo, ChannelStats)>,
    compressions: BTreeSet<String>,
    indexed: bool,
    warnings: Vec<String>,
}

/// Lists the topics of a bag (its directory or `.mcap` file) from the files' summaries, or by
/// a linear scan of the files that have none.
pub fn info(path: &Path) -> Result<BagInfo> {
    let bag = BagFiles::resolve(path)?;
    let mut topics: BTreeMap<String, (ChannelInfo, ChannelStats)> = BTreeMap::new();
    let mut compressions = BTreeSet::new();
    let mut profiles = BTreeSet::new();
    let mut indexed = true;
    let mut warnings = Vec::new();
    for (k, file) in bag.files.iter().enumerate() {
        let fi = match summary_info(file)? {
            Ok(fi) => fi,
            Err(reason) => {
                let mut fi = linear_info(file, k as u32)?;
                fi.warnings.insert(
                    0,
                    format!("{}: {reason}; the file was scanned", file.display()),
                );
                fi
            }
        };
        indexed &= fi.indexed;
        profiles.insert(fi.profile);
        compressions.extend(fi.compressions);
        warnings.extend(fi.warnings);
        for (c, s) in fi.channels {
            let entry = topics.entry(c.topic.clone()).or_insert((
                c,
                ChannelStats {
                    count: 0,
                    first_ns: u64::MAX,
                    last_ns: 0,
                },
            ));
            if s.count > 0 {
                entry.1.count += s.count;
                entry.1.first_ns = entry.1.first_ns.min(s.first_ns);
                entry.1.last_ns = entry.1.last_ns.max(s.last_ns);
            }
        }
    }
    let secs = |ns: u64| ns as f64 * 1e-9;
    let topics: Vec<TopicInfo> = topics
        .into_iter()
        .map(|(name, (c, s))| {
            let span = s.count > 0;
            let dt = secs(s.last_ns.saturating_sub(s.first_ns));
            TopicInfo {
                name,
                type_name: normalize_type(&c.schema_name),
                message_encoding: c.message_encoding,
                message_count: s.count,
                first_secs: span.then(|| secs(s.first_ns)),
                last_secs: span.then(|| secs(s.last_ns)),
                rate_hz: (s.count > 1 && dt > 0.0).then(|| (s.count - 1) as f64 / dt),
            }
        })
        .collect();
    let start = topics.iter().filter_map(|t| t.first_secs).reduce(f64::min);
    let end = topics.iter().filter_map(|t| t.last_secs).reduce(f64::max);
    Ok(BagInfo {
        file_size_bytes: bag.size_bytes(),
        path: bag.path,
        files: bag.files,
        storage: "mcap".into(),
        profile: profiles.into_iter().collect::<Vec<_>>().join(", "),
        compression: compressions
            .into_iter()
            .map(|c| if c.is_empty() { "none".into() } else { c })
            .collect(),
        indexed,
        message_count: topics.iter().map(|t| t.message_count).sum(),
        start_secs: start,
        end_secs: end,
        duration_secs: match (start, end) {
            (Some(s), Some(e)) => e - s,
            _ => 0.0,
        },
        topics,
        warnings,
    })
}

fn linear_info(file: &Path, index: u32) -> Result<FileInfo> {
    let mut reader = McapReader::open(file, index, Arc::new(|_| None))?;
    while reader.next_message()?.is_some() {}
    let stats = reader.channel_stats();
    let mut channels: Vec<(ChannelInfo, ChannelStats)> = reader
        .channels()
        .map(|c| (c.clone(), stats.get(&c.id).copied().unwrap_or_default()))
        .collect();
    channels.sort_by_key(|(c, _)| c.id);
    Ok(FileInfo {
        profile: reader.profile().to_string(),
        channels,
        compressions: reader.compressions().clone(),
        indexed: false,
        warnings: reader.take_warnings(),
    })
}

fn read_summary(file: &mut File, len: u64) -> std::result::Result<Option<mcap::Summary>, String> {
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(len)
            .with_record_length_limit(len as usize),
    );
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| e.to_string())? {
            SummaryReadEvent::ReadRequest(n) => {
                let read = file.read(reader.insert(n)).map_err(|e| e.to_string())?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).map_err(|e| e.to_string())?;
                reader.notify_seeked(pos);
            }
        }
    }
    Ok(reader.finish())
}

/// The log times of channel `id` in the message index record at `offset`.
fn index_times(file: &mut File, len: u64, offset: u64, id: u16) -> Option<(u64, u64)> {
    let mut head = [0u8; 9];
    file.seek(SeekFrom::Start(offset)).ok()?;
    file.read_exact(&mut head).ok()?;
    let body_len = u64::from_le_bytes(head[1..].try_into().ok()?);
    if head[0] != 0x07 || body_len > len.saturating_sub(offset + 9) {
        return None;
    }
    let mut body = vec![0u8; body_len as usize];
    file.read_exact(&mut body).ok()?;
    match mcap::parse_record(0x07, &body).ok()? {
        mcap::records::Record::MessageIndex(index) if index.channel_id == id => {
            let times = index.records.iter().map(|r| r.log_time);
            Some((times.clone().min()?, times.max()?))
        }
        _ => None,
    }
}

/// The file's topics from its summary; the reason when it has none usable (no footer, no
/// statistics, messages outside indexed chunks).
fn summary_info(path: &Path) -> Result<std::result::Result<FileInfo, String>> {
    let profile = McapReader::open(path, 0, Arc::new(|_| None))?
        .profile()
        .to_string();
    let mut file = File::open(path).map_err(|e| Error::io(path, Location::File, e))?;
    let len = file
        .metadata()
        .map_err(|e| Error::io(path, Location::File, e))?
        .len();
    let mut tail = [0u8; 8];
    let ends_with_magic = len >= 16
        && file.seek(SeekFrom::End(-8)).is_ok()
        && file.read_exact(&mut tail).is_ok()
        && &tail == super::bag::MAGIC;
    if !ends_with_magic {
        return Ok(Err(
            "the file has no footer (the recording was not closed, or the file is truncated)"
                .into(),
        ));
    }
    let summary = match read_summary(&mut file, len) {
        Ok(Some(summary)) => summary,
        Ok(None) => return Ok(Err("the file has no summary section".into())),
        Err(e) => return Ok(Err(format!("the summary cannot be read: {e}"))),
    };
    let Some(stats) = &summary.stats else {
        return Ok(Err("the summary has no statistics".into()));
    };
    let indexed_count: usize = summary
        .chunk_indexes
        .iter()
        .map(|c| c.message_index_offsets.len())
        .sum();
    if stats.message_count > 0 && indexed_count == 0 {
        return Ok(Err("the summary has no message indexes".into()));
    }
    let mut channels = Vec::new();
    let mut ids: Vec<u16> = summary.channels.keys().copied().collect();
    ids.sort_unstable();
    for id in ids {
        let c = &summary.channels[&id];
        let info = ChannelInfo {
            id,
            topic: c.topic.clone(),
            message_encoding: c.message_encoding.clone(),
            schema_name: c
                .schema
                .as_ref()
                .map(|s| s.name.clone())
                .unwrap_or_default(),
            schema_encoding: c
                .schema
                .as_ref()
                .map(|s| s.encoding.clone())
                .unwrap_or_default(),
        };
        let count = stats.channel_message_counts.get(&id).copied().unwrap_or(0);
        let mut with: Vec<_> = summary
            .chunk_indexes
            .iter()
            .filter_map(|ci| ci.message_index_offsets.get(&id).map(|&o| (ci, o)))
            .collect();
        with.sort_by_key(|(ci, _)| ci.message_start_time);
        let first = with
            .first()
            .and_then(|&(_, o)| index_times(&mut file, len, o, id));
        let last = with
            .iter()
            .rev()
            .filter_map(|&(_, o)| index_times(&mut file, len, o, id))
            .next();
        let (first_ns, last_ns) = match (first, last) {
            (Some(f), Some(l)) => (f.0.min(l.0), f.1.max(l.1)),
            _ if count == 0 => (0, 0),
            _ => return Ok(Err(format!("no message index for {}", c.topic))),
        };
        channels.push((
            info,
            ChannelStats {
                count,
                first_ns,
                last_ns,
            },
        ));
    }
    Ok(Ok(FileInfo {
        profile,
        channels,
        compressions: summary
            .chunk_indexes
            .iter()
            .map(|c| c.compression.clone())
            .collect(),
        indexed: true,
        warnings: Vec::new(),
    }))
}

impl fmt::Display for BagInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "bag:         {}", self.path.display())?;
        writeln!(
            f,
            "files:       {} ({:.1} MB), storage {}, profile {}",
            self.files.len(),
            self.file_size_bytes as f64 / 1e6,
            self.storage,
            if self.profile.is_empty() {
                "(none)"
            } else {
                &self.profile
            }
        )?;
        writeln!(
            f,
            "compression: {}{}",
            if self.compression.is_empty() {
                "none".into()
            } else {
                self.compression.join(", ")
            },
            if self.indexed {
                ""
            } else {
                " (no summary: scanned)"
            }
        )?;
        if let (Some(s), Some(e)) = (self.start_secs, self.end_secs) {
            writeln!(
                f,
                "time:        {:.3} s from {s:.3} s to {e:.3} s",
                self.duration_secs
            )?;
        }
        writeln!(f, "messages:    {}", self.message_count)?;
        let w = self.topics.iter().map(|t| t.name.len()).max().unwrap_or(0);
        let tw = self
            .topics
            .iter()
            .map(|t| t.type_name.len())
            .max()
            .unwrap_or(0);
        for t in &self.topics {
            let rate = t.rate_hz.map_or("-".into(), |r| format!("{r:.2} Hz"));
            writeln!(
                f,
                "  {:w$}  {:tw$}  {:>8} msgs  {:>10}  {}",
                t.name, t.type_name, t.message_count, rate, t.message_encoding
            )?;
        }
        for warning in &self.warnings {
            writeln!(f, "warning: {warning}")?;
        }
        Ok(())
    }
}
