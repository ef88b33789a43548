//! Scans decoded on other threads while the poses of earlier ones are computed: batches of
//! raw messages go to a few threads and come back decoded, in file order.

use std::collections::VecDeque;
use std::ops::Range;
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use std::sync::{Arc, Mutex};

use raypath_geometry::Scan2;

use crate::rosbag::cdr::CdrError;
use crate::rosbag::msgs::{self, Stamp};
use crate::rosbag::reader::MessageLoc;

/// Messages per batch.
pub(super) const BATCH: usize = 64;
/// Decoding threads at most (and no more than the machine's cores).
const MAX_THREADS: usize = 4;

/// A decoded scan: its stamp, its frame (a range of [`Batch::frame`]) and the scan.
pub(super) type Decoded = Result<(Stamp, Range<usize>, Scan2), CdrError>;

/// A message of a batch.
pub(super) struct Item {
    /// Index of its file in the recording.
    pub(super) file: usize,
    pub(super) log_time: u64,
    pub(super) loc: MessageLoc,
    range: Range<usize>,
    /// Filled by [`Batch::decode`].
    pub(super) decoded: Option<Decoded>,
}

/// Raw scans, then decoded ones; buffers reused from batch to batch.
#[derive(Default)]
pub(super) struct Batch {
    bytes: Vec<u8>,
    pub(super) items: Vec<Item>,
    frames: String,
}

impl Batch {
    /// Adds a raw message.
    pub(super) fn push(&mut self, file: usize, log_time: u64, loc: MessageLoc, data: &[u8]) {
        let start = self.bytes.len();
        self.bytes.extend_from_slice(data);
        self.items.push(Item {
            file,
            log_time,
            loc,
            range: start..self.bytes.len(),
            decoded: None,
        });
    }

    fn clear(&mut self) {
        self.bytes.clear();
        self.items.clear();
        self.frames.clear();
    }

    fn decode(&mut self) {
        let Batch {
            bytes,
            items,
            frames,
        } = self;
        for item in items {
            let decoded = msgs::decode_scan(&bytes[item.range.clone()]).map(|(header, scan)| {
                let start = frames.len();
                frames.push_str(header.frame_id);
                (header.stamp, start..frames.len(), scan)
            });
            item.decoded = Some(decoded);
        }
    }

    /// The frame id at `range`.
    pub(super) fn frame(&self, range: &Range<usize>) -> &str {
        self.frames.get(range.clone()).unwrap_or_default()
    }
}

type Sent = (Batch, SyncSender<Batch>);

/// Batches being decoded (by threads, or here on a single core), oldest first.
pub(super) struct Decoders {
    jobs: Option<Sender<Sent>>,
    pending: VecDeque<Receiver<Batch>>,
    done: VecDeque<Batch>,
    spare: Vec<Batch>,
    threads: usize,
}

impl Decoders {
    /// Threads on a machine with two cores or more.
    pub(super) fn start() -> Self {
        let n = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(MAX_THREADS);
        let mut threads = 0;
        let mut jobs = None;
        if n >= 2 {
            let (tx, rx) = mpsc::channel::<Sent>();
            let rx = Arc::new(Mutex::new(rx));
            for _ in 0..n {
                let rx = Arc::clone(&rx);
                let spawned = std::thread::Builder::new()
                    .name("rosbag-scans".into())
                    .spawn(move || work(&rx));
                threads += usize::from(spawned.is_ok());
            }
            jobs = (threads > 0).then_some(tx);
        }
        Self {
            jobs,
            pending: VecDeque::new(),
            done: VecDeque::new(),
            spare: Vec::new(),
            threads,
        }
    }

    /// True when another batch may be read ahead.
    pub(super) fn has_room(&self) -> bool {
        self.pending.len() + self.done.len() < 2 * self.threads.max(1)
    }

    /// An empty batch.
    pub(super) fn batch(&mut self) -> Batch {
        self.spare.pop().unwrap_or_default()
    }

    /// Gives back a batch whose scans were taken.
    pub(super) fn recycle(&mut self, mut batch: Batch) {
        batch.clear();
        self.spare.push(batch);
    }

    /// Decodes `batch` (on a thread when there are threads).
    pub(super) fn submit(&mut self, mut batch: Batch) {
        if let Some(jobs) = &self.jobs {
            let (done, rx) = mpsc::sync_channel(1);
            match jobs.send((batch, done)) {
                Ok(()) => {
                    self.pending.push_back(rx);
                    return;
                }
                Err(mpsc::SendError((returned, _))) => batch = returned,
            }
        }
        batch.decode();
        self.done.push_back(batch);
    }

    /// The oldest batch, decoded; `None` when none is left.
    pub(super) fn next(&mut self) -> Result<Option<Batch>, String> {
        if let Some(rx) = self.pending.pop_front() {
            return rx
                .recv()
                .map(Some)
                .map_err(|_| "a scan decoding thread failed".to_string());
        }
        Ok(self.done.pop_front())
    }
}

fn work(jobs: &Mutex<Receiver<Sent>>) {
    loop {
        let next = match jobs.lock() {
            Ok(rx) => rx.recv(),
            Err(_) => return,
        };
        let Ok((mut batch, done)) = next else {
            return;
        };
        batch.decode();
        // The reader may have stopped (and dropped the receiver): nothing to do then.
        let _ = done.send(batch);
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::rosbag::cdr::CdrWriter;

    /// Batches come back in order, decoded as `decode_scan` decodes them (bad messages too).
    #[test]
    fn batches_come_back_in_order() {
        let mut decoders = Decoders::start();
        let mut w = CdrWriter::new();
        let mut messages = Vec::new();
        for k in 0..(5 * BATCH + 3) {
            w.reset();
            let scan = Scan2 {
                angle_min_rad: -1.0,
                angle_increment_rad: 0.01,
                max_range_m: 30.0,
                ranges: (0..50)
                    .map(|i| f64::from((i * k as u32) % 300) * 0.1)
                    .collect(),
                intensities: None,
            };
            let stamp = Stamp {
                sec: k as i32,
                nanosec: 5,
            };
            msgs::encode_scan(&mut w, stamp, &format!("laser{}", k % 3), &scan);
            let mut bytes = w.bytes().to_vec();
            if k % 17 == 5 {
                bytes.truncate(bytes.len() / 2);
            }
            messages.push(bytes);
        }
        let loc = MessageLoc {
            file: 0,
            record_offset: 0,
            index: 0,
        };
        let mut got = Vec::new();
        let mut chunks = messages.chunks(BATCH);
        loop {
            while decoders.has_room() {
                let Some(chunk) = chunks.next() else {
                    break;
                };
                let mut batch = decoders.batch();
                for (i, m) in chunk.iter().enumerate() {
                    batch.push(0, i as u64, loc, m);
                }
                decoders.submit(batch);
            }
            let Some(mut batch) = decoders.next().unwrap() else {
                break;
            };
            for i in 0..batch.items.len() {
                let decoded = batch.items[i].decoded.take().unwrap();
                got.push(decoded.map(|(stamp, frame, scan)| {
                    (stamp, batch.frame(&frame).to_string(), scan.ranges)
                }));
            }
            decoders.recycle(batch);
        }
        assert_eq!(got.len(), messages.len());
        for (m, g) in messages.iter().zip(got) {
            let want = msgs::decode_scan(m)
                .map(|(h, scan)| (h.stamp, h.frame_id.to_string(), scan.ranges));
            match (want, g) {
                (Ok(a), Ok(b)) => assert_eq!(a, b),
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                (a, b) => panic!("{a:?} vs {b:?}"),
            }
        }
    }
}
