//! The records of a chunk, and the schemas and channels they define: chunks decoded into a
//! buffer of message records, uncompressed ones in place, compressed ones by the `mcap`
//! crate's sans-io reader.

use std::collections::{BTreeSet, HashMap};

use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::reader::{
    ChannelInfo, Classify, MESSAGE_HEAD, OP_CHANNEL, OP_MESSAGE, OP_SCHEMA, RECORD_HEAD,
};

/// Chunks that claim more than this many uncompressed bytes are rejected.
const MAX_CHUNK_BYTES: u64 = 1 << 32;

/// Schemas, channels and roles seen so far.
pub(super) struct Channels {
    pub(super) schemas: HashMap<u16, (String, String)>,
    pub(super) channels: HashMap<u16, ChannelInfo>,
    pub(super) roles: HashMap<u16, u8>,
    pub(super) stats: HashMap<u16, ChannelStats>,
    pub(super) compressions: BTreeSet<String>,
    pub(super) prefix_role: Option<u8>,
    pub(super) classify: Classify,
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
    pub(super) fn count(&mut self, message: &[u8]) {
        if message.len() < MESSAGE_HEAD {
            return;
        }
        let id = u16::from_le_bytes([message[0], message[1]]);
        let t = u64::from_le_bytes([
            message[6],
            message[7],
            message[8],
            message[9],
            message[10],
            message[11],
            message[12],
            message[13],
        ]);
        let s = self.stats.entry(id).or_insert(ChannelStats {
            count: 0,
            first_ns: t,
            last_ns: t,
        });
        s.count += 1;
        s.first_ns = s.first_ns.min(t);
        s.last_ns = s.last_ns.max(t);
    }
}

impl Channels {
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
                match (self.classify)(&info) {
                    Some(role) => self.roles.insert(c.id, role),
                    None => self.roles.remove(&c.id),
                };
                self.channels.insert(c.id, info);
            }
            _ => {}
        }
        Ok(())
    }
}

/// Messages of a prefix-only role are kept up to this many bytes (enough for their header).
const PREFIX_BYTES: usize = MESSAGE_HEAD + 4096;

/// Handles one record found inside a chunk: registers schemas and channels, appends messages
/// to `out` (empty placeholders for messages not kept).
fn chunk_record(
    opcode: u8,
    data: &[u8],
    channels: &mut Channels,
    keep_all: bool,
    out: &mut Vec<u8>,
) -> Result<(), String> {
    match opcode {
        OP_SCHEMA | OP_CHANNEL => channels.register(opcode, data)?,
        OP_MESSAGE => {
            channels.count(data);
            let role = (data.len() >= MESSAGE_HEAD)
                .then(|| channels.roles.get(&u16::from_le_bytes([data[0], data[1]])))
                .flatten()
                .copied();
            let keep = match role {
                _ if data.len() < MESSAGE_HEAD => 0,
                _ if keep_all => data.len(),
                Some(r) if Some(r) == channels.prefix_role => data.len().min(PREFIX_BYTES),
                Some(_) => data.len(),
                None => 0,
            };
            out.push(OP_MESSAGE);
            out.extend_from_slice(&(keep as u64).to_le_bytes());
            out.extend_from_slice(&data[..keep]);
        }
        _ => {}
    }
    Ok(())
}

/// Decodes the chunk record `record` (opcode and length included; cut short when not
/// `complete`) into `out`, registering schemas and channels on the way and keeping the
/// messages of channels with a role (all with `keep_all`). Uncompressed chunks are read in
/// place; compressed ones are decompressed whole by the `mcap` crate's sans-io reader (after
/// checking their CRC) or, when cut short, as far as they go. Returns the problem in words.
pub(super) fn decode_chunk(
    record: &[u8],
    complete: bool,
    channels: &mut Channels,
    keep_all: bool,
    out: &mut Vec<u8>,
) -> Result<(), String> {
    out.clear();
    let body = record.get(RECORD_HEAD..).unwrap_or_default();
    let u64_at = |at: usize| -> Option<u64> {
        body.get(at..at.checked_add(8)?)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
    };
    let uncompressed = u64_at(16).unwrap_or(0);
    let name_len = body
        .get(28..32)
        .and_then(|b| b.try_into().ok())
        .map_or(0, u32::from_le_bytes) as usize;
    let name = body.get(32..32usize.saturating_add(name_len));
    if let Some(name) = name
        && !channels
            .compressions
            .contains(&*String::from_utf8_lossy(name))
    {
        channels
            .compressions
            .insert(String::from_utf8_lossy(name).into_owned());
    }
    if uncompressed > MAX_CHUNK_BYTES {
        return Err(format!("chunk claims {uncompressed} uncompressed bytes"));
    }
    if name.is_some_and(<[u8]>::is_empty) {
        // Uncompressed: the records follow the header.
        let Some(size) = u64_at(32) else {
            return if complete {
                Err("chunk header is cut short".into())
            } else {
                Ok(())
            };
        };
        let records = &body[40.min(body.len())..];
        let records = &records[..records
            .len()
            .min(usize::try_from(size).unwrap_or(usize::MAX))];
        if complete && (records.len() as u64) < size {
            return Err(format!("chunk records of {size} bytes exceed the chunk"));
        }
        let mut p = 0;
        while p + RECORD_HEAD <= records.len() {
            let opcode = records[p];
            let len = u64::from_le_bytes(
                records[p + 1..p + RECORD_HEAD]
                    .try_into()
                    .unwrap_or_default(),
            );
            let start = p + RECORD_HEAD;
            let Some(end) = usize::try_from(len).ok().and_then(|l| start.checked_add(l)) else {
                return Err(format!("record length {len} in the chunk is impossible"));
            };
            if end > records.len() {
                if complete {
                    return Err(format!("a record of {len} bytes overruns the chunk"));
                }
                break;
            }
            chunk_record(opcode, &records[start..end], channels, keep_all, out)?;
            p = end;
        }
        return Ok(());
    }
    let limit = (uncompressed as usize)
        .max(record.len())
        .saturating_add(RECORD_HEAD);
    // Decompress the whole chunk at once (fast) unless it is cut short or claims an
    // implausible ratio (then record by record, never allocating what it claims up front).
    let whole = complete && uncompressed <= 64 * record.len() as u64 + (1 << 16);
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_validate_chunk_crcs(true)
            .with_prevalidate_chunk_crcs(whole)
            .with_record_length_limit(limit),
    );
    let mut src = record;
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| e.to_string())? {
            LinearReadEvent::ReadRequest(n) => {
                if src.is_empty() {
                    break;
                }
                let k = n.min(src.len());
                reader.insert(k).copy_from_slice(&src[..k]);
                reader.notify_read(k);
                src = &src[k..];
            }
            LinearReadEvent::Record { opcode, data } => {
                chunk_record(opcode, data, channels, keep_all, out)?;
            }
        }
    }
    Ok(())
}
