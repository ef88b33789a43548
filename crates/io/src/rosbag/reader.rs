//! Streaming MCAP reading over a `File`: top-level records framed here (so every message has
//! a place in the file to come back to), chunks decoded by [`ChunkBuf`] into reused buffers,
//! messages handed out one at a time.

use std::collections::{BTreeSet, HashMap};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::bag::MAGIC;
pub use super::chunk::ChannelStats;
use super::chunk::{Channels, ChunkBuf, chunk_compression, message_head, record_head};
use crate::error::{Error, Location, Result};

mod prefetch;
mod reread;

use prefetch::Lookahead;
pub use reread::ChunkCache;

const OP_HEADER: u8 = 0x01;
const OP_FOOTER: u8 = 0x02;
pub(super) const OP_SCHEMA: u8 = 0x03;
pub(super) const OP_CHANNEL: u8 = 0x04;
pub(super) const OP_MESSAGE: u8 = 0x05;
const OP_CHUNK: u8 = 0x06;
const OP_DATA_END: u8 = 0x0F;
/// Opcode and length of a record.
pub(super) const RECORD_HEAD: usize = 9;
/// Channel id, sequence, log time, publish time.
pub(super) const MESSAGE_HEAD: usize = 2 + 4 + 8 + 8;
/// Out-of-order warnings per file before they are only counted.
const MAX_ORDER_WARNINGS: usize = 5;

/// A channel of an MCAP file with its schema.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelInfo {
    /// Channel id (per file).
    pub id: u16,
    /// Topic name.
    pub topic: String,
    /// `message_encoding` (`cdr` for ROS 2).
    pub message_encoding: String,
    /// Schema name, the message type (`sensor_msgs/msg/LaserScan`).
    pub schema_name: String,
    /// Schema encoding (`ros2msg`, `ros2idl`; `ros1msg` in ROS 1 recordings).
    pub schema_encoding: String,
}

/// Decides which channels' messages are read: a role number, or `None` to skip them.
pub type Classify = Arc<dyn Fn(&ChannelInfo) -> Option<u8> + Send + Sync>;

/// Where a message is in its file, to read it again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MessageLoc {
    /// Index of the file in the recording.
    pub file: u32,
    /// Offset of the chunk record holding the message, or of the message record itself.
    pub record_offset: u64,
    /// Ordinal of the message among the message records of its chunk; `u32::MAX` for a
    /// message outside chunks.
    pub index: u32,
}

/// A message handed out by [`McapReader::next_message`].
#[derive(Clone, Copy, Debug)]
pub struct Message<'a> {
    /// The channel's role.
    pub role: u8,
    /// The channel's topic.
    pub topic: &'a str,
    /// Log time in nanoseconds.
    pub log_time: u64,
    /// The serialized message.
    pub data: &'a [u8],
    /// Where it is.
    pub loc: MessageLoc,
}

/// Messages of a prefix-only role are handed out up to this many bytes (enough for their
/// header).
const PREFIX_BYTES: usize = MESSAGE_HEAD + 4096;

/// Reads the messages of one MCAP file in file order.
pub struct McapReader {
    path: PathBuf,
    file_index: u32,
    file: BufReader<File>,
    len: u64,
    pos: u64,
    record: Vec<u8>,
    chunk: ChunkBuf,
    in_chunk: bool,
    channels: Channels,
    profile: String,
    order_warnings: usize,
    last_delivered: Option<(u16, u64)>,
    warnings: Vec<String>,
    truncated_chunk: Option<(u64, u64)>,
    done: bool,
    /// Chunks decompressed ahead on other threads (started at the first compressed chunk).
    lookahead: Option<Lookahead>,
    lookahead_tried: bool,
    /// The path, shared with the threads that read ahead.
    shared_path: Option<Arc<Path>>,
}

enum Found {
    InChunk(usize, usize, u32),
    Record,
}

impl McapReader {
    /// Opens `path`, checks the magic and reads the header record (profile).
    pub fn open(path: &Path, file_index: u32, classify: Classify) -> Result<Self> {
        let file = File::open(path).map_err(|e| Error::io(path, Location::File, e))?;
        let len = file
            .metadata()
            .map_err(|e| Error::io(path, Location::File, e))?
            .len();
        let mut reader = Self {
            path: path.to_path_buf(),
            file_index,
            // Small: after a chunk decoded ahead is skipped, only a few index records are read.
            file: BufReader::with_capacity(1 << 13, file),
            len,
            pos: 0,
            record: Vec::new(),
            chunk: ChunkBuf::default(),
            in_chunk: false,
            channels: Channels::new(classify),
            profile: String::new(),
            order_warnings: 0,
            last_delivered: None,
            warnings: Vec::new(),
            truncated_chunk: None,
            done: false,
            lookahead: None,
            lookahead_tried: false,
            shared_path: None,
        };
        let mut magic = [0u8; 8];
        if len < 8 || reader.file.read_exact(&mut magic).is_err() || &magic != MAGIC {
            return Err(Error::UnknownFormat {
                path: path.to_path_buf(),
                reason: "not an MCAP file (it does not start with the MCAP magic)".into(),
            });
        }
        reader.pos = 8;
        if let Some((OP_HEADER, body_len)) = reader.peek_head()? {
            reader.read_record(body_len)?;
            if let Ok(mcap::records::Record::Header(h)) =
                mcap::parse_record(OP_HEADER, &reader.record[RECORD_HEAD..])
            {
                reader.profile = h.profile;
            }
        }
        Ok(reader)
    }

    /// The header's profile (`ros2`, `ros1`, or empty).
    pub fn profile(&self) -> &str {
        &self.profile
    }

    /// The channels seen so far.
    pub fn channels(&self) -> impl Iterator<Item = &ChannelInfo> {
        self.channels.iter()
    }

    /// The channel `id`.
    pub fn channel(&self, id: u16) -> Option<&ChannelInfo> {
        self.channels.get(id)
    }

    /// Keeps only the first few kilobytes (the header) of the messages of `role`.
    pub fn set_prefix_only(&mut self, role: u8) {
        self.channels.prefix_role = Some(role);
    }

    /// Message counts and log-time spans per channel id so far (of every channel).
    pub fn channel_stats(&self) -> HashMap<u16, ChannelStats> {
        self.channels.stats()
    }

    /// The chunk compressions seen so far (`""` for uncompressed chunks).
    pub fn compressions(&self) -> &BTreeSet<String> {
        &self.channels.compressions
    }

    /// Takes the warnings so far.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn malformed(&self, at: u64, reason: impl Into<String>) -> Error {
        Error::malformed(&self.path, Location::Byte(at), reason)
    }

    fn last_message_words(&self) -> String {
        match self.last_delivered {
            Some((id, t)) => format!(
                "the last message read is on {} at log time {:.9} s",
                self.channel(id).map_or("?", |c| c.topic.as_str()),
                t as f64 * 1e-9
            ),
            None => "no message was read before it".into(),
        }
    }

    /// Opcode and body length of the record at `pos`, or `None` at the end of the file
    /// (with a warning when the file ends without its footer).
    fn peek_head(&mut self) -> Result<Option<(u8, u64)>> {
        if self.pos + RECORD_HEAD as u64 > self.len {
            if self.pos != self.len {
                let words = self.last_message_words();
                self.warnings.push(format!(
                    "{}: byte {}: the file is truncated inside a record header; {words}",
                    self.path.display(),
                    self.pos
                ));
            } else {
                self.warnings.push(format!(
                    "{}: the file ends without a footer (the recording was not closed); the \
                     messages were read by a linear scan",
                    self.path.display()
                ));
            }
            return Ok(None);
        }
        let mut head = [0u8; RECORD_HEAD];
        self.file
            .read_exact(&mut head)
            .map_err(|e| Error::io(&self.path, Location::Byte(self.pos), e))?;
        self.file
            .seek_relative(-(RECORD_HEAD as i64))
            .map_err(|e| Error::io(&self.path, Location::Byte(self.pos), e))?;
        let len = u64::from_le_bytes([
            head[1], head[2], head[3], head[4], head[5], head[6], head[7], head[8],
        ]);
        Ok(Some((head[0], len)))
    }

    /// Reads the record at `pos` with up to `body_len` body bytes (fewer when the file ends
    /// first) into `self.record`, and moves `pos` past it; true when it was complete.
    fn read_record(&mut self, body_len: u64) -> Result<bool> {
        let avail = self.len - self.pos - RECORD_HEAD as u64;
        let take = body_len.min(avail);
        let total = RECORD_HEAD + take as usize;
        self.record.resize(total, 0);
        self.file
            .read_exact(&mut self.record[..total])
            .map_err(|e| Error::io(&self.path, Location::Byte(self.pos), e))?;
        self.pos += total as u64;
        Ok(take == body_len)
    }

    fn skip_record(&mut self, body_len: u64) -> Result<bool> {
        let avail = self.len - self.pos - RECORD_HEAD as u64;
        if body_len > avail {
            return Ok(false);
        }
        let step = RECORD_HEAD as u64 + body_len;
        self.file
            .seek_relative(step as i64)
            .map_err(|e| Error::io(&self.path, Location::Byte(self.pos), e))?;
        self.pos += step;
        Ok(true)
    }

    /// Reads the chunk whose record starts at `pos` and decodes it (lazily when only the
    /// first bytes of some messages are wanted).
    fn load_chunk(&mut self, body_len: u64) -> Result<()> {
        let at = self.pos;
        let complete = self.read_record(body_len)?;
        if let Some(name) = chunk_compression(&self.record)
            && !self
                .channels
                .compressions
                .contains(&*String::from_utf8_lossy(name))
        {
            self.channels
                .compressions
                .insert(String::from_utf8_lossy(name).into_owned());
        }
        let lazy = complete && self.channels.prefix_role.is_some();
        self.chunk.offset = at;
        if let Err(reason) = self.chunk.load(&mut self.record, complete, lazy) {
            return Err(self.malformed(at, format!("chunk: {reason}")));
        }
        self.in_chunk = true;
        if !complete {
            self.done = true;
            self.truncated_chunk = Some((at, body_len));
        }
        Ok(())
    }

    /// Moves to the chunk at `pos`: decoded ahead, or now (and then, when it is compressed
    /// and wanted whole, the chunks after it are decoded ahead from now on).
    fn next_chunk(&mut self, body_len: u64) -> Result<()> {
        let at = self.pos;
        if let Some(ahead) = self.lookahead.as_mut()
            && let Some(result) = ahead.take(at, &mut self.chunk)
        {
            if let Err(reason) = result {
                return Err(self.malformed(at, format!("chunk: {reason}")));
            }
            let name = self.chunk.compression_name();
            if !self.channels.compressions.contains(name) {
                self.channels.compressions.insert(name.to_string());
            }
            self.chunk.offset = at;
            self.in_chunk = true;
            // The look-ahead found the whole record: it is in the file.
            self.skip_record(body_len)?;
            if let Some(ahead) = self.lookahead.as_mut() {
                ahead.top_up();
            }
            return Ok(());
        }
        self.load_chunk(body_len)?;
        let wanted_whole =
            self.chunk.compressed() && self.chunk.complete() && self.channels.prefix_role.is_none();
        if wanted_whole && !self.lookahead_tried {
            self.lookahead_tried = true;
            self.lookahead = Lookahead::open(&self.path, self.file_index, self.len);
        }
        if let Some(ahead) = self.lookahead.as_mut()
            && wanted_whole
        {
            ahead.restart(self.pos);
            ahead.top_up();
        }
        Ok(())
    }

    /// Decodes the current chunk up to byte `upto`; false when it does not go that far.
    fn fill(&mut self, upto: usize) -> Result<bool> {
        self.chunk
            .fill(upto)
            .map_err(|reason| self.malformed(self.chunk.offset, format!("chunk: {reason}")))
    }

    /// The next message with a role in the current chunk (registering schemas and channels
    /// and counting messages on the way), or `None` at its end.
    fn next_in_chunk(&mut self) -> Result<Option<Found>> {
        loop {
            let p = self.chunk.pos;
            if p + RECORD_HEAD > self.chunk.end() || !self.fill(p + RECORD_HEAD)? {
                return Ok(None);
            }
            let (opcode, len) = record_head(self.chunk.bytes(p, p + RECORD_HEAD), 0);
            let start = p + RECORD_HEAD;
            let stop = match usize::try_from(len).ok().and_then(|l| start.checked_add(l)) {
                Some(stop) if stop <= self.chunk.end() => stop,
                _ if self.chunk.complete() => {
                    return Err(self.malformed(
                        self.chunk.offset,
                        format!("chunk: a record of {len} bytes overruns the chunk"),
                    ));
                }
                _ => return Ok(None),
            };
            match opcode {
                OP_MESSAGE => {
                    let head_end = (start + MESSAGE_HEAD).min(stop);
                    if !self.fill(head_end)? {
                        return Ok(None);
                    }
                    let head = self.chunk.bytes(start, head_end);
                    self.channels.count(head);
                    let role = message_head(head).and_then(|(id, _)| self.channels.role(id));
                    let index = self.chunk.next_index;
                    self.chunk.next_index += 1;
                    let Some(role) = role else {
                        self.chunk.pos = stop;
                        continue;
                    };
                    let keep = if Some(role) == self.channels.prefix_role {
                        stop.min(start + PREFIX_BYTES)
                    } else {
                        stop
                    };
                    // A message cut short by the end of the file is not handed out, even when
                    // only its first bytes are wanted.
                    let need = if self.chunk.complete() { keep } else { stop };
                    if !self.fill(need)? {
                        return Ok(None);
                    }
                    self.chunk.pos = stop;
                    return Ok(Some(Found::InChunk(start, keep, index)));
                }
                OP_SCHEMA | OP_CHANNEL => {
                    if !self.fill(stop)? {
                        return Ok(None);
                    }
                    if let Err(reason) = self
                        .channels
                        .register(opcode, self.chunk.bytes(start, stop))
                    {
                        return Err(self.malformed(self.chunk.offset, format!("chunk: {reason}")));
                    }
                    self.chunk.pos = stop;
                }
                _ => self.chunk.pos = stop,
            }
        }
    }

    /// The next message of a channel with a role, or `None` at the end of the file (or of
    /// what could be read of it: see [`McapReader::warnings`]).
    pub fn next_message(&mut self) -> Result<Option<Message<'_>>> {
        let found = loop {
            if self.in_chunk {
                if let Some(found) = self.next_in_chunk()? {
                    break found;
                }
                self.in_chunk = false;
                if let Some((at, body_len)) = self.truncated_chunk.take() {
                    let words = self.last_message_words();
                    self.warnings.push(format!(
                        "{}: byte {at}: the file is truncated inside a chunk of {body_len} \
                         bytes: the messages before the cut were read, the rest of the \
                         chunk is lost; {words}",
                        self.path.display()
                    ));
                }
                continue;
            }
            if self.done {
                return Ok(None);
            }
            let Some((opcode, body_len)) = self.peek_head()? else {
                self.done = true;
                return Ok(None);
            };
            match opcode {
                OP_CHUNK => self.next_chunk(body_len)?,
                OP_MESSAGE | OP_SCHEMA | OP_CHANNEL => {
                    let at = self.pos;
                    if !self.read_record(body_len)? {
                        let words = self.last_message_words();
                        self.warnings.push(format!(
                            "{}: byte {at}: the file is truncated inside a record; {words}",
                            self.path.display()
                        ));
                        self.done = true;
                        continue;
                    }
                    let body = &self.record[RECORD_HEAD..];
                    if opcode != OP_MESSAGE {
                        if let Err(reason) = self.channels.register(opcode, body) {
                            return Err(self.malformed(at, reason));
                        }
                        continue;
                    }
                    self.channels.count(body);
                    if body.len() >= MESSAGE_HEAD
                        && self
                            .channels
                            .role(u16::from_le_bytes([body[0], body[1]]))
                            .is_some()
                    {
                        self.chunk.offset = at;
                        break Found::Record;
                    }
                }
                OP_DATA_END | OP_FOOTER => {
                    self.done = true;
                }
                _ => {
                    if !self.skip_record(body_len)? {
                        let words = self.last_message_words();
                        self.warnings.push(format!(
                            "{}: byte {}: the file is truncated inside a record (opcode \
                             {opcode:#04x}); {words}",
                            self.path.display(),
                            self.pos
                        ));
                        self.done = true;
                    }
                }
            }
        };
        let (body, loc) = match found {
            Found::InChunk(start, end, index) => (
                self.chunk.bytes(start, end),
                MessageLoc {
                    file: self.file_index,
                    record_offset: self.chunk.offset,
                    index,
                },
            ),
            Found::Record => (
                &self.record[RECORD_HEAD..],
                MessageLoc {
                    file: self.file_index,
                    record_offset: self.chunk.offset,
                    index: u32::MAX,
                },
            ),
        };
        let channel_id = u16::from_le_bytes([body[0], body[1]]);
        let log_time = u64::from_le_bytes([
            body[6], body[7], body[8], body[9], body[10], body[11], body[12], body[13],
        ]);
        let role = self.channels.role(channel_id).unwrap_or(0);
        if let Some(prev) = self.channels.handed_out(channel_id, log_time)
            && log_time < prev
        {
            self.order_warnings += 1;
            if self.order_warnings <= MAX_ORDER_WARNINGS {
                let topic = self.channel(channel_id).map_or("?", |c| c.topic.as_str());
                self.warnings.push(format!(
                    "{}: {topic}: log time {:.9} s comes after {:.9} s (messages out of order)",
                    self.path.display(),
                    log_time as f64 * 1e-9,
                    prev as f64 * 1e-9
                ));
            }
        }
        self.last_delivered = Some((channel_id, log_time));
        let topic = self.channel(channel_id).map_or("", |c| c.topic.as_str());
        Ok(Some(Message {
            role,
            topic,
            log_time,
            data: &body[MESSAGE_HEAD..],
            loc,
        }))
    }

    /// Out-of-order messages beyond the warnings listed.
    pub fn unlisted_order_warnings(&self) -> usize {
        self.order_warnings.saturating_sub(MAX_ORDER_WARNINGS)
    }

    fn seek_to(&mut self, at: u64) -> Result<()> {
        self.file
            .seek(SeekFrom::Start(at))
            .map_err(|e| Error::io(&self.path, Location::Byte(at), e))?;
        self.pos = at;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
