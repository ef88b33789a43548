//! Messages read again at the places a first pass found them (point clouds, read on
//! demand): the last chunk decoded is kept, and when the messages are read in order the
//! chunks of the next ones are decoded ahead on other threads.

use std::sync::Arc;

use super::prefetch::Ahead;
use super::{McapReader, MessageLoc, OP_CHUNK, OP_MESSAGE};
use crate::error::Result;
use crate::rosbag::chunk::{ChunkBuf, record_head};
use crate::rosbag::reader::{MESSAGE_HEAD, RECORD_HEAD};

impl McapReader {
    /// Reads the message at `loc` again (the file's channels must have been read up to it:
    /// they are, after a pass over the file). The chunk is decoded into `cache` (or taken
    /// from the chunks decoded ahead) unless it is there already.
    pub fn reread(&mut self, loc: MessageLoc, cache: &mut ChunkCache) -> Result<Reread> {
        let at = loc.record_offset;
        let missing = || "the message is no longer where the first pass found it".to_string();
        if at + RECORD_HEAD as u64 > self.len {
            return Err(self.malformed(at, missing()));
        }
        if loc.index == u32::MAX {
            self.seek_to(at)?;
            let Some((OP_MESSAGE, body_len)) = self.peek_head()? else {
                return Err(self.malformed(at, missing()));
            };
            if !self.read_record(body_len)? || self.record.len() < RECORD_HEAD + MESSAGE_HEAD {
                return Err(self.malformed(at, missing()));
            }
            return Ok(Reread(Held::Copied(
                self.record[RECORD_HEAD + MESSAGE_HEAD..].to_vec(),
            )));
        }
        if cache.key != Some((loc.file, at)) {
            cache.key = None;
            // The chunk handed out last may still be in use elsewhere: then a new one.
            if Arc::get_mut(&mut cache.chunk).is_none() {
                cache.chunk = Arc::default();
            }
            let Some(chunk) = Arc::get_mut(&mut cache.chunk) else {
                return Err(self.malformed(at, missing()));
            };
            let ahead = cache.ahead.as_mut();
            let result = match ahead.and_then(|a| a.take((loc.file, at), chunk)) {
                Some(result) => result,
                None => {
                    self.seek_to(at)?;
                    let Some((OP_CHUNK, body_len)) = self.peek_head()? else {
                        return Err(self.malformed(at, missing()));
                    };
                    let complete = self.read_record(body_len)?;
                    chunk.load(&mut self.record, complete, false)
                }
            };
            result.map_err(|reason| self.malformed(at, format!("chunk: {reason}")))?;
            message_ranges(chunk, &mut cache.starts);
            cache.key = Some((loc.file, at));
        }
        match cache.starts.get(loc.index as usize) {
            Some(&(start, stop)) if stop - start >= MESSAGE_HEAD => Ok(Reread(Held::InChunk(
                Arc::clone(&cache.chunk),
                start + MESSAGE_HEAD,
                stop,
            ))),
            _ => Err(self.malformed(at, missing())),
        }
    }
}

/// The body ranges of the message records of a decoded chunk, in order.
fn message_ranges(chunk: &ChunkBuf, out: &mut Vec<(usize, usize)>) {
    out.clear();
    let end = chunk.end();
    let mut p = chunk.pos;
    while p + RECORD_HEAD <= end {
        let (opcode, len) = record_head(chunk.bytes(p, p + RECORD_HEAD), 0);
        let start = p + RECORD_HEAD;
        let Some(stop) = usize::try_from(len)
            .ok()
            .and_then(|l| start.checked_add(l))
            .filter(|&stop| stop <= end)
        else {
            break;
        };
        if opcode == OP_MESSAGE {
            out.push((start, stop));
        }
        p = stop;
    }
}

/// A message read again by [`McapReader::reread`]: in its decoded chunk (shared, not copied)
/// or copied out of its record.
pub struct Reread(Held);

enum Held {
    InChunk(Arc<ChunkBuf>, usize, usize),
    Copied(Vec<u8>),
}

impl Reread {
    /// The serialized message.
    pub fn bytes(&self) -> &[u8] {
        match &self.0 {
            Held::InChunk(chunk, start, end) => chunk.bytes(*start, *end),
            Held::Copied(bytes) => bytes,
        }
    }
}

/// The last chunk decoded for random access, and the chunks decoded ahead.
#[derive(Default)]
pub struct ChunkCache {
    key: Option<(u32, u64)>,
    chunk: Arc<ChunkBuf>,
    starts: Vec<(usize, usize)>,
    ahead: Option<Ahead>,
    ahead_tried: bool,
}

/// Chunks looked at for [`McapReader::prefetch`] at most.
const PREFETCH_LOOK: usize = 64;

impl McapReader {
    /// Starts decoding the chunks of `next` (the messages to be read again next, in that
    /// order) on other threads, as many as fit ahead (messages of other files and outside
    /// chunks end the list). Problems are left for [`McapReader::reread`] to report.
    pub fn prefetch(&mut self, next: impl Iterator<Item = MessageLoc>, cache: &mut ChunkCache) {
        if !cache.ahead_tried {
            cache.ahead_tried = true;
            cache.ahead = Ahead::start();
        }
        let Some(ahead) = cache.ahead.as_mut() else {
            return;
        };
        for loc in next.take(PREFETCH_LOOK) {
            let key = (loc.file, loc.record_offset);
            if loc.file != self.file_index || loc.index == u32::MAX {
                break;
            }
            if cache.key == Some(key) || ahead.contains(key) {
                continue;
            }
            if !ahead.has_room() {
                break;
            }
            let Ok(Some(size)) = self.chunk_size_at(loc.record_offset) else {
                break;
            };
            let path = self
                .shared_path
                .get_or_insert_with(|| Arc::from(self.path.as_path()));
            ahead.submit(key, path, loc.record_offset, size);
        }
    }

    /// The size of the chunk record at `at` when a whole one is there.
    fn chunk_size_at(&mut self, at: u64) -> Result<Option<usize>> {
        if at + RECORD_HEAD as u64 > self.len {
            return Ok(None);
        }
        self.seek_to(at)?;
        Ok(match self.peek_head()? {
            Some((OP_CHUNK, body_len)) if body_len <= self.len - at - RECORD_HEAD as u64 => {
                usize::try_from(body_len + RECORD_HEAD as u64).ok()
            }
            _ => None,
        })
    }
}
