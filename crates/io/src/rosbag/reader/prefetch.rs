//! Chunks decompressed ahead of the reader on worker threads and handed back in order: while
//! the messages of one chunk are decoded, the next chunks are being decompressed.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use std::sync::{Arc, Mutex};

use super::{OP_CHANNEL, OP_CHUNK, OP_DATA_END, OP_FOOTER, OP_MESSAGE, OP_SCHEMA, RECORD_HEAD};
use crate::rosbag::chunk::ChunkBuf;

/// Worker threads at most (and no more than the machine's cores).
const MAX_WORKERS: usize = 4;
/// Chunks decoded ahead at most.
const DEPTH: usize = 4;
/// Compressed bytes read ahead at most (one chunk more is always allowed).
const MAX_AHEAD_BYTES: u64 = 64 << 20;

/// A chunk record with the buffers it is decoded into, on its way to a worker and back.
struct Job {
    chunk: ChunkBuf,
    record: Vec<u8>,
    /// The file, offset and size of the record, for the worker to read.
    source: Option<(Arc<Path>, u64, usize)>,
    result: Result<(), String>,
    /// The worker could not read the record (the reader will, and report why).
    unread: bool,
}

type Sent = (Job, SyncSender<Job>);

/// Threads reading and decompressing whole chunks; they end when this is dropped.
struct Workers {
    jobs: Sender<Sent>,
}

impl Workers {
    /// The workers, or `None` on a single core (or when no thread can be started).
    fn start() -> Option<Self> {
        let n = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(MAX_WORKERS);
        if n < 2 {
            return None;
        }
        let (jobs, rx) = mpsc::channel::<Sent>();
        let rx = Arc::new(Mutex::new(rx));
        let mut started = 0;
        for _ in 0..n {
            let rx = Arc::clone(&rx);
            let spawned = std::thread::Builder::new()
                .name("rosbag-chunks".into())
                .spawn(move || work(&rx));
            started += usize::from(spawned.is_ok());
        }
        (started > 0).then_some(Self { jobs })
    }
}

fn work(jobs: &Mutex<Receiver<Sent>>) {
    let mut open: Option<(Arc<Path>, File)> = None;
    loop {
        let next = match jobs.lock() {
            Ok(rx) => rx.recv(),
            Err(_) => return,
        };
        let Ok((mut job, done)) = next else {
            return;
        };
        if let Some((path, offset, size)) = job.source.take() {
            job.unread = read_at(&mut open, &path, offset, size, &mut job.record).is_err();
        }
        if !job.unread {
            job.result = job.chunk.load(&mut job.record, true, false);
        }
        // The reader may have moved on (and dropped the receiver): nothing to do then.
        let _ = done.send(job);
    }
}

/// Reads `size` bytes at `offset` of `path` into `out` (keeping the file open for the next).
fn read_at(
    open: &mut Option<(Arc<Path>, File)>,
    path: &Arc<Path>,
    offset: u64,
    size: usize,
    out: &mut Vec<u8>,
) -> std::io::Result<()> {
    let file = match open {
        Some((p, f)) if p == path => f,
        _ => &mut open.insert((Arc::clone(path), File::open(path)?)).1,
    };
    file.seek(SeekFrom::Start(offset))?;
    out.resize(size, 0);
    file.read_exact(out)
}

/// Chunks submitted for decoding, keyed (file, offset) in the order they will be wanted.
pub(crate) struct Ahead {
    workers: Workers,
    pending: VecDeque<((u32, u64), u64, Receiver<Job>)>,
    spare: Vec<(ChunkBuf, Vec<u8>)>,
    bytes: u64,
}

impl Ahead {
    /// `None` on a single core.
    pub(crate) fn start() -> Option<Self> {
        Some(Self {
            workers: Workers::start()?,
            pending: VecDeque::new(),
            spare: Vec::new(),
            bytes: 0,
        })
    }

    /// True when another chunk may be read ahead.
    pub(crate) fn has_room(&self) -> bool {
        self.pending.is_empty() || (self.pending.len() < DEPTH && self.bytes < MAX_AHEAD_BYTES)
    }

    /// True when the chunk `key` is pending.
    pub(crate) fn contains(&self, key: (u32, u64)) -> bool {
        self.pending.iter().any(|(k, _, _)| *k == key)
    }

    /// Submits the complete chunk record of `size` bytes at `offset` of `path` as `key`, for
    /// a worker to read and decode.
    pub(crate) fn submit(&mut self, key: (u32, u64), path: &Arc<Path>, offset: u64, size: usize) {
        let (chunk, record) = self.spare.pop().unwrap_or_default();
        let (done, rx) = mpsc::sync_channel(1);
        let job = Job {
            chunk,
            record,
            source: Some((Arc::clone(path), offset, size)),
            result: Ok(()),
            unread: false,
        };
        if self.workers.jobs.send((job, done)).is_ok() {
            self.pending.push_back((key, size as u64, rx));
            self.bytes += size as u64;
        }
    }

    /// The chunk `key` when it is the next one decoded ahead: waits for it and swaps it into
    /// `chunk` (whose buffers are kept for later chunks). `None` (and anything pending
    /// dropped) when `key` is not next, or when the worker could not read it.
    pub(crate) fn take(
        &mut self,
        key: (u32, u64),
        chunk: &mut ChunkBuf,
    ) -> Option<Result<(), String>> {
        if self.pending.front().is_none_or(|(k, _, _)| *k != key) {
            self.clear();
            return None;
        }
        let (_, size, rx) = self.pending.pop_front()?;
        self.bytes -= size;
        let Ok(mut job) = rx.recv() else {
            return Some(Err("a decompression thread failed".into()));
        };
        if job.unread {
            self.clear();
            self.spare.push((job.chunk, job.record));
            return None;
        }
        std::mem::swap(chunk, &mut job.chunk);
        self.spare.push((job.chunk, job.record));
        Some(job.result)
    }

    /// Drops what is pending.
    pub(crate) fn clear(&mut self) {
        self.pending.clear();
        self.bytes = 0;
    }
}

/// Reads a file's chunks ahead of the reader, past the records the reader skips (message
/// indexes, attachments, metadata); it stops at anything else, or a record cut short, and
/// leaves that to the reader.
pub(super) struct Lookahead {
    path: Arc<Path>,
    file: BufReader<File>,
    file_index: u32,
    len: u64,
    pos: u64,
    stopped: bool,
    ahead: Ahead,
}

impl Lookahead {
    /// A second handle on the file at `path`; `None` on a single core.
    pub(super) fn open(path: &Path, file_index: u32, len: u64) -> Option<Self> {
        let file = File::open(path).ok()?;
        Some(Self {
            path: Arc::from(path),
            file: BufReader::with_capacity(1 << 12, file),
            file_index,
            len,
            pos: 0,
            stopped: true,
            ahead: Ahead::start()?,
        })
    }

    /// Starts looking ahead again from byte `pos`, the record after a chunk the reader
    /// decoded itself.
    pub(super) fn restart(&mut self, pos: u64) {
        self.ahead.clear();
        self.stopped = self.file.seek(SeekFrom::Start(pos)).is_err();
        self.pos = pos;
    }

    /// The chunk at byte `at` when it was decoded ahead (see [`Ahead::take`]).
    pub(super) fn take(&mut self, at: u64, chunk: &mut ChunkBuf) -> Option<Result<(), String>> {
        let taken = self.ahead.take((self.file_index, at), chunk);
        if taken.is_none() {
            self.stopped = true;
        }
        taken
    }

    /// Submits chunks until enough are ahead.
    pub(super) fn top_up(&mut self) {
        while !self.stopped && self.ahead.has_room() {
            self.stopped = !self.step();
        }
    }

    /// Looks at the next record: false when the look-ahead stops there.
    fn step(&mut self) -> bool {
        if self.pos + RECORD_HEAD as u64 > self.len {
            return false;
        }
        let mut head = [0u8; RECORD_HEAD];
        if self.file.read_exact(&mut head).is_err() {
            return false;
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&head[1..]);
        let body_len = u64::from_le_bytes(len);
        if body_len > self.len - self.pos - RECORD_HEAD as u64 {
            return false;
        }
        let total = RECORD_HEAD as u64 + body_len;
        match head[0] {
            OP_CHUNK => {
                let Ok(size) = usize::try_from(total) else {
                    return false;
                };
                let key = (self.file_index, self.pos);
                self.ahead.submit(key, &self.path, self.pos, size);
            }
            OP_MESSAGE | OP_SCHEMA | OP_CHANNEL | OP_DATA_END | OP_FOOTER => return false,
            _ => {}
        }
        if self.file.seek_relative(body_len as i64).is_err() {
            return false;
        }
        self.pos += total;
        true
    }
}
