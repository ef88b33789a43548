//! The records of a chunk, and the schemas and channels they define. Uncompressed chunks are
//! read in place; zstd and LZ4 chunks are decompressed in one call into a reused buffer, or
//! streamed as far as needed (a chunk cut short, one claiming an implausible size, or when
//! only the first bytes of its last message are wanted).

use std::collections::{BTreeSet, HashMap};

use lz4_frame::{Lz4Frames, Step as Lz4Step};

use super::reader::{ChannelInfo, Classify, MESSAGE_HEAD, RECORD_HEAD};

/// Chunks that claim more than this many uncompressed bytes are rejected.
const MAX_CHUNK_BYTES: u64 = 1 << 32;
/// Streamed output grows by at least this many bytes at a time.
const STREAM_STEP: usize = 1 << 16;
/// Offset of the compression name in a chunk record's body.
const NAME_AT: usize = 32;

/// Schemas, channels and roles seen so far.
pub(super) struct Channels {
    pub(super) schemas: HashMap<u16, (String, String)>,
    /// By channel id.
    channels: Vec<Option<ChannelInfo>>,
    /// By channel id.
    slots: Vec<Slot>,
    pub(super) compressions: BTreeSet<String>,
    pub(super) prefix_role: Option<u8>,
    classify: Classify,
}

/// What is kept per channel id.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    role: Option<u8>,
    stats: Option<ChannelStats>,
    /// Log time of the last message handed out.
    last_log: Option<u64>,
}

/// Message count and log-time span of a channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChannelStats {
    /// Messages.
    pub count: u64,
    /// First log time, nanoseconds.
    pub first_ns: u64,
    /// Last log time, nanoseconds.
    pub last_ns: u64,
}

impl Channels {
    pub(super) fn new(classify: Classify) -> Self {
        Self {
            schemas: HashMap::new(),
            channels: Vec::new(),
            slots: Vec::new(),
            compressions: BTreeSet::new(),
            prefix_role: None,
            classify,
        }
    }

    fn slot(&mut self, id: u16) -> &mut Slot {
        let i = usize::from(id);
        if i >= self.slots.len() {
            self.slots.resize(i + 1, Slot::default());
        }
        &mut self.slots[i]
    }

    /// The role of channel `id`.
    pub(super) fn role(&self, id: u16) -> Option<u8> {
        self.slots.get(usize::from(id)).and_then(|s| s.role)
    }

    /// The channel `id`.
    pub(super) fn get(&self, id: u16) -> Option<&ChannelInfo> {
        self.channels.get(usize::from(id)).and_then(Option::as_ref)
    }

    /// The channels, by id.
    pub(super) fn iter(&self) -> impl Iterator<Item = &ChannelInfo> {
        self.channels.iter().flatten()
    }

    /// Message counts and log-time spans of the channels with messages.
    pub(super) fn stats(&self) -> HashMap<u16, ChannelStats> {
        (0..=u16::MAX)
            .zip(&self.slots)
            .filter_map(|(id, s)| Some((id, s.stats?)))
            .collect()
    }

    /// Records the log time of a message of channel `id` handed out; the previous one.
    pub(super) fn handed_out(&mut self, id: u16, log_time: u64) -> Option<u64> {
        self.slot(id).last_log.replace(log_time)
    }

    /// Counts a message (its first [`MESSAGE_HEAD`] bytes are enough).
    pub(super) fn count(&mut self, message: &[u8]) {
        let Some((id, t)) = message_head(message) else {
            return;
        };
        let s = self.slot(id).stats.get_or_insert(ChannelStats {
            count: 0,
            first_ns: t,
            last_ns: t,
        });
        s.count += 1;
        s.first_ns = s.first_ns.min(t);
        s.last_ns = s.last_ns.max(t);
    }

    /// Registers a schema or channel record.
    pub(super) fn register(&mut self, opcode: u8, body: &[u8]) -> Result<(), String> {
        let record = mcap::parse_record(opcode, body).map_err(|e| e.to_string())?;
        match record {
            mcap::records::Record::Schema { header, .. } => {
                self.schemas
                    .insert(header.id, (header.name, header.encoding));
            }
            mcap::records::Record::Channel(c) => {
                let (schema_name, schema_encoding) =
                    self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                let info = ChannelInfo {
                    id: c.id,
                    topic: c.topic,
                    message_encoding: c.message_encoding,
                    schema_name,
                    schema_encoding,
                };
                self.slot(c.id).role = (self.classify)(&info);
                let i = usize::from(c.id);
                if i >= self.channels.len() {
                    self.channels.resize(i + 1, None);
                }
                self.channels[i] = Some(info);
            }
            _ => {}
        }
        Ok(())
    }
}

/// Channel id and log time of a message record's body.
pub(super) fn message_head(message: &[u8]) -> Option<(u16, u64)> {
    let head = message.get(..MESSAGE_HEAD)?;
    let id = u16::from_le_bytes([head[0], head[1]]);
    let mut t = [0u8; 8];
    t.copy_from_slice(&head[6..14]);
    Some((id, u64::from_le_bytes(t)))
}

/// Opcode and body length of the record at `p` of `data` (which must hold its head).
pub(super) fn record_head(data: &[u8], p: usize) -> (u8, u64) {
    let mut len = [0u8; 8];
    len.copy_from_slice(&data[p + 1..p + RECORD_HEAD]);
    (data[p], u64::from_le_bytes(len))
}

/// The compression name of the chunk record `record` (opcode and length included), when its
/// header goes that far.
pub(super) fn chunk_compression(record: &[u8]) -> Option<&[u8]> {
    let body = record.get(RECORD_HEAD..)?;
    let name_len = u32::from_le_bytes(body.get(28..NAME_AT)?.try_into().ok()?) as usize;
    body.get(NAME_AT..NAME_AT.checked_add(name_len)?)
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Codec {
    #[default]
    None,
    Zstd,
    Lz4,
}

/// What is still to decompress of a chunk.
#[derive(Default)]
enum Stream {
    #[default]
    Done,
    /// zstd input left in `ChunkBuf::input[at..stop]`.
    Zstd { at: usize, stop: usize },
    /// LZ4 frames in `ChunkBuf::input[..stop]`, decoded up to `frames.at`.
    Lz4 { frames: Lz4Frames, stop: usize },
}

/// The records of one chunk (`[opcode][u64 length][body]` each), decoded as far as asked.
/// Buffers and decompression contexts are reused from chunk to chunk.
#[derive(Default)]
pub(super) struct ChunkBuf {
    /// The chunk record as read, while its records are streamed out of it.
    input: Vec<u8>,
    /// Decoded records, valid in `begin..filled`.
    data: Vec<u8>,
    begin: usize,
    filled: usize,
    /// Where the records end (`begin` + their declared size).
    end: usize,
    /// The next record.
    pub(super) pos: usize,
    /// File offset of the chunk record.
    pub(super) offset: u64,
    /// Ordinal of the next message record.
    pub(super) next_index: u32,
    stream: Stream,
    codec: Codec,
    crc: u32,
    complete: bool,
    /// The claimed size is at most 64 times the compressed one (plus 64 KiB).
    plausible: bool,
    zstd: Option<zstd::bulk::Decompressor<'static>>,
    zstd_stream: Option<zstd::stream::raw::Decoder<'static>>,
}

impl ChunkBuf {
    /// Takes the chunk record `record` (opcode and length included; cut short when not
    /// `complete`; `record` gets a spare buffer back) and decodes its records: all of them
    /// now unless `lazy`, else as [`ChunkBuf::fill`] asks. Uncompressed records are read in
    /// place; compressed ones are decompressed in one call when the chunk is complete and its
    /// size plausible, else streamed (never allocating more than what comes out). Returns the
    /// problem in words.
    pub(super) fn load(
        &mut self,
        record: &mut Vec<u8>,
        complete: bool,
        lazy: bool,
    ) -> Result<(), String> {
        self.stream = Stream::Done;
        self.begin = 0;
        self.filled = 0;
        self.end = 0;
        self.pos = 0;
        self.next_index = 0;
        self.complete = complete;
        let cut = || {
            if complete {
                Err("chunk header is cut short".to_string())
            } else {
                Ok(())
            }
        };
        let body = record.get(RECORD_HEAD..).unwrap_or_default();
        let u64_at = |at: usize| -> Option<u64> {
            body.get(at..at.checked_add(8)?)
                .and_then(|b| b.try_into().ok())
                .map(u64::from_le_bytes)
        };
        let Some(uncompressed) = u64_at(16) else {
            return cut();
        };
        let Some(name) = chunk_compression(record) else {
            return cut();
        };
        self.crc = body
            .get(24..28)
            .and_then(|b| b.try_into().ok())
            .map_or(0, u32::from_le_bytes);
        self.codec = match name {
            b"" => Codec::None,
            b"zstd" => Codec::Zstd,
            b"lz4" => Codec::Lz4,
            other => {
                return Err(format!(
                    "unsupported chunk compression {:?}",
                    String::from_utf8_lossy(other)
                ));
            }
        };
        if uncompressed > MAX_CHUNK_BYTES {
            return Err(format!("chunk claims {uncompressed} uncompressed bytes"));
        }
        let size_at = NAME_AT + name.len();
        let Some(size) = u64_at(size_at) else {
            return cut();
        };
        let start = RECORD_HEAD + size_at + 8;
        let stop = record
            .len()
            .min(start.saturating_add(usize::try_from(size).unwrap_or(usize::MAX)));
        if complete && ((stop - start) as u64) < size {
            return Err(format!("chunk records of {size} bytes exceed the chunk"));
        }
        if self.codec == Codec::None {
            std::mem::swap(record, &mut self.data);
            self.begin = start;
            self.pos = start;
            // Whole, or as far as the file goes.
            self.filled = stop;
            self.end = stop;
            return Ok(());
        }
        let total = uncompressed as usize;
        self.end = total;
        std::mem::swap(record, &mut self.input);
        // One call for a whole chunk, unless it is cut short or claims an implausible ratio
        // (then streamed, never allocating what it claims up front).
        self.plausible = uncompressed <= 64 * (stop - start) as u64 + (1 << 16);
        if complete && !lazy && self.plausible {
            self.decompress_whole(start, stop, total)?;
            return self.finish();
        }
        self.stream = match self.codec {
            Codec::Lz4 => Stream::Lz4 {
                frames: Lz4Frames::at(start),
                stop,
            },
            _ => {
                let decoder = match &mut self.zstd_stream {
                    Some(d) => d,
                    None => self
                        .zstd_stream
                        .insert(zstd::stream::raw::Decoder::new().map_err(|e| e.to_string())?),
                };
                zstd::stream::raw::Operation::reinit(decoder).map_err(|e| e.to_string())?;
                Stream::Zstd { at: start, stop }
            }
        };
        if !lazy {
            self.fill(total)?;
        }
        Ok(())
    }

    fn decompress_whole(&mut self, start: usize, stop: usize, total: usize) -> Result<(), String> {
        if self.codec == Codec::Lz4 {
            self.stream = Stream::Lz4 {
                frames: Lz4Frames::at(start),
                stop,
            };
            self.data.clear();
            self.data.reserve(total);
            return self.fill(total).map(|_| ());
        }
        if self.data.len() < total {
            self.data.resize(total, 0);
        }
        let z = match &mut self.zstd {
            Some(z) => z,
            None => self
                .zstd
                .insert(zstd::bulk::Decompressor::new().map_err(|e| e.to_string())?),
        };
        self.filled = z
            .decompress_to_buffer(&self.input[start..stop], &mut self.data[..total])
            .map_err(|e| format!("zstd: {e} (the chunk header says {total} bytes)"))?;
        Ok(())
    }

    /// Decodes the records up to byte `upto` (at most to their end) when they are there;
    /// true when they are.
    pub(super) fn fill(&mut self, upto: usize) -> Result<bool, String> {
        let upto = upto.min(self.end);
        while self.filled < upto && !matches!(self.stream, Stream::Done) {
            let progress = match self.stream {
                Stream::Lz4 { .. } => self.lz4_step()?,
                _ => self.zstd_step(upto)?,
            };
            if self.filled == self.end {
                let extra = self.drain()?;
                self.stream = Stream::Done;
                if extra && self.complete {
                    return Err(format!(
                        "chunk decompresses to more than its {} bytes",
                        self.end - self.begin
                    ));
                }
                self.finish()?;
            } else if !progress {
                self.stream = Stream::Done;
                if self.complete {
                    return Err(format!(
                        "chunk decompresses to {} bytes, its header says {}",
                        self.filled - self.begin,
                        self.end - self.begin
                    ));
                }
                self.end = self.filled;
            }
        }
        Ok(self.filled >= upto)
    }

    /// Decodes the next LZ4 block (straight into the buffer); false at the end of the input.
    fn lz4_step(&mut self) -> Result<bool, String> {
        let Stream::Lz4 { frames, stop } = &mut self.stream else {
            return Ok(false);
        };
        // A chunk with a CRC is checked by it: the frames' own checksums are not needed.
        let check = self.crc == 0;
        self.data.truncate(self.filled);
        let step = frames.step(&self.input[..*stop], &mut self.data, self.end, check);
        self.filled = self.data.len();
        Ok(matches!(step?, Lz4Step::Progress))
    }

    /// One zstd streaming step into `data[filled..]`, no further than `upto` (a lazy chunk
    /// stops there; a chunk claiming an implausible size grows its buffer step by step with
    /// what comes out); false when nothing more comes.
    fn zstd_step(&mut self, upto: usize) -> Result<bool, String> {
        let want = if self.plausible {
            upto
        } else {
            upto.min(self.filled.saturating_mul(2).max(self.filled + STREAM_STEP))
        };
        if self.data.len() < want {
            self.data.resize(want, 0);
        }
        let mut out = std::mem::take(&mut self.data);
        let r = self.zstd_into(&mut out[self.filled..want]);
        self.data = out;
        let (read, written) = r?;
        self.filled += written;
        Ok(read > 0 || written > 0)
    }

    fn zstd_into(&mut self, out: &mut [u8]) -> Result<(usize, usize), String> {
        let Stream::Zstd { at, stop } = &mut self.stream else {
            return Ok((0, 0));
        };
        let decoder = self
            .zstd_stream
            .as_mut()
            .ok_or("the zstd decoder is gone")?;
        let status =
            zstd::stream::raw::Operation::run_on_buffers(decoder, &self.input[*at..*stop], out)
                .map_err(|e| format!("zstd: {e}"))?;
        *at += status.bytes_read;
        Ok((status.bytes_read, status.bytes_written))
    }

    /// After the declared size came out: reads the rest of the stream (an LZ4 frame's end
    /// mark and checksum); true when more would come out.
    fn drain(&mut self) -> Result<bool, String> {
        match self.stream {
            Stream::Lz4 { .. } => {
                while self.lz4_step()? {}
                let Stream::Lz4 { frames, .. } = &self.stream else {
                    return Ok(false);
                };
                if self.complete && frames.in_frame() {
                    return Err("lz4: the frame is cut short".into());
                }
                Ok(false)
            }
            _ => {
                let mut probe = [0u8; 1];
                loop {
                    match self.zstd_into(&mut probe)? {
                        (_, 1..) => return Ok(true),
                        (0, 0) => return Ok(false),
                        _ => {}
                    }
                }
            }
        }
    }

    /// Checks a complete chunk decoded whole: its declared size, its CRC when it has one.
    fn finish(&mut self) -> Result<(), String> {
        if !self.complete {
            self.end = self.filled;
            return Ok(());
        }
        if self.filled != self.end {
            return Err(format!(
                "chunk decompresses to {} bytes, its header says {}",
                self.filled - self.begin,
                self.end - self.begin
            ));
        }
        if self.codec != Codec::None && self.crc != 0 {
            let mut crc = flate2::Crc::new();
            crc.update(&self.data[self.begin..self.end]);
            if crc.sum() != self.crc {
                // The `mcap` crate's words, as before.
                return Err(format!(
                    "Chunk CRC failed (expected {:08X}, got {:08X})",
                    self.crc,
                    crc.sum()
                ));
            }
        }
        Ok(())
    }

    /// The decoded bytes `range` (they must have been filled).
    pub(super) fn bytes(&self, start: usize, end: usize) -> &[u8] {
        &self.data[start..end]
    }

    /// Where the records end (known once all are decoded for a chunk cut short).
    pub(super) fn end(&self) -> usize {
        self.end
    }

    /// The chunk's compression as MCAP names it (`""` for none).
    pub(super) fn compression_name(&self) -> &'static str {
        match self.codec {
            Codec::None => "",
            Codec::Zstd => "zstd",
            Codec::Lz4 => "lz4",
        }
    }

    /// True when the chunk is compressed.
    pub(super) fn compressed(&self) -> bool {
        self.codec != Codec::None
    }

    /// True when the chunk record was whole.
    pub(super) fn complete(&self) -> bool {
        self.complete
    }
}

mod lz4_frame;
#[cfg(test)]
mod tests;
