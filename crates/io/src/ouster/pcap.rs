//! UDP datagrams from packet captures: classic pcap (microsecond and nanosecond, either byte
//! order) and pcapng (section, interface, enhanced/simple/obsolete packet blocks), over
//! Ethernet (with 802.1Q tags), Linux cooked capture v1/v2, BSD loopback or raw IP; IPv4
//! (fragments reassembled) and IPv6 without extension headers.
//!
//! Formats: pcap per the tcpdump `pcap-savefile(5)` page, pcapng per IETF draft
//! `draft-ietf-opsawg-pcapng`; IPv4 fragment reassembly per RFC 791 §3.2.

use std::io::BufRead;
use std::path::Path;

use super::net;
use crate::error::{Error, Location, Result};
use crate::source::ByteReader;

/// Largest capture record or pcapng block the reader accepts (bounds allocation on corrupt
/// length fields; a jumbo UDP datagram is at most 64 KiB).
const MAX_RECORD: usize = 1 << 20;

/// One UDP datagram of the capture.
#[derive(Debug)]
pub(crate) struct Datagram<'a> {
    /// File offset of the capture record (the first fragment's, for a reassembled datagram).
    pub record_offset: u64,
    /// File offset of the payload's first byte (in the first fragment when reassembled).
    pub payload_offset: u64,
    /// Capture time, seconds (UNIX time as the capturing host saw it).
    pub stamp_s: f64,
    /// UDP destination port.
    pub dst_port: u16,
    /// The UDP payload.
    pub payload: &'a [u8],
}

/// Counts of what the reader passed over.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CaptureStats {
    /// Capture records (packets) read.
    pub records: u64,
    /// Records that are not UDP over IPv4/IPv6 (ARP, TCP, …), skipped.
    pub not_udp: u64,
    /// IPv4 fragments read.
    pub fragments: u64,
    /// Datagrams reassembled from fragments.
    pub reassembled: u64,
    /// Fragmented datagrams never completed (evicted, or pending at the end of the file).
    pub incomplete: u64,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Interface {
    link: u32,
    /// Seconds per timestamp tick.
    tick_s: f64,
}

/// What a reader knows after the file header: enough to resume reading at a record offset.
#[derive(Clone, Debug)]
pub(crate) enum CaptureFormat {
    /// Classic pcap.
    Classic {
        big_endian: bool,
        tick_s: f64,
        link: u32,
    },
    /// pcapng, with the interfaces of the current section.
    Ng {
        big_endian: bool,
        interfaces: Vec<Interface>,
    },
}

/// Where the current datagram's bytes are.
struct Found {
    record_offset: u64,
    payload_offset: u64,
    stamp_s: f64,
    dst_port: u16,
    in_assembled: bool,
    start: usize,
    end: usize,
}

/// Streams the UDP datagrams of a capture.
pub(crate) struct PcapReader<R> {
    bytes: ByteReader<R>,
    format: CaptureFormat,
    record: Vec<u8>,
    reassembler: net::Reassembler,
    stats: CaptureStats,
}

fn u16_at(b: &[u8], at: usize, big: bool) -> u16 {
    let v = [b[at], b[at + 1]];
    if big {
        u16::from_be_bytes(v)
    } else {
        u16::from_le_bytes(v)
    }
}

fn u32_at(b: &[u8], at: usize, big: bool) -> u32 {
    let v = [b[at], b[at + 1], b[at + 2], b[at + 3]];
    if big {
        u32::from_be_bytes(v)
    } else {
        u32::from_le_bytes(v)
    }
}

/// True when `head` starts like a pcap or pcapng file.
pub(crate) fn is_capture(head: &[u8]) -> bool {
    head.len() >= 4
        && matches!(
            [head[0], head[1], head[2], head[3]],
            [0xd4, 0xc3, 0xb2, 0xa1]
                | [0xa1, 0xb2, 0xc3, 0xd4]
                | [0x4d, 0x3c, 0xb2, 0xa1]
                | [0xa1, 0xb2, 0x3c, 0x4d]
                | [0x0a, 0x0d, 0x0d, 0x0a]
        )
}

impl<R: BufRead> PcapReader<R> {
    /// Reads the file header from `reader`; `name` is used in errors.
    pub fn new(reader: R, name: &Path) -> Result<Self> {
        let mut bytes = ByteReader::new(reader, name, 0);
        let mut magic = [0u8; 4];
        bytes.read_exact(&mut magic, "capture file magic")?;
        let format = match magic {
            [0xd4, 0xc3, 0xb2, 0xa1] | [0xa1, 0xb2, 0xc3, 0xd4] => {
                Self::classic_header(&mut bytes, magic[0] == 0xa1, 1e-6)?
            }
            [0x4d, 0x3c, 0xb2, 0xa1] | [0xa1, 0xb2, 0x3c, 0x4d] => {
                Self::classic_header(&mut bytes, magic[0] == 0xa1, 1e-9)?
            }
            [0x0a, 0x0d, 0x0d, 0x0a] => {
                let mut reader = Self::with_format(
                    bytes,
                    CaptureFormat::Ng {
                        big_endian: false,
                        interfaces: Vec::new(),
                    },
                );
                reader.section_header(0)?;
                return Ok(reader);
            }
            _ => {
                return Err(Error::malformed(
                    name,
                    Location::Byte(0),
                    format!(
                        "not a pcap or pcapng capture (magic {:02x}{:02x}{:02x}{:02x})",
                        magic[0], magic[1], magic[2], magic[3]
                    ),
                ));
            }
        };
        Ok(Self::with_format(bytes, format))
    }

    /// Continues reading a capture whose header was read by another reader: `reader` is
    /// positioned at byte `offset`, the start of a record (classic pcap) or block (pcapng).
    pub fn resume(reader: R, name: &Path, format: CaptureFormat, offset: u64) -> Self {
        Self::with_format(ByteReader::new(reader, name, offset), format)
    }

    fn with_format(bytes: ByteReader<R>, format: CaptureFormat) -> Self {
        Self {
            bytes,
            format,
            record: Vec::new(),
            reassembler: net::Reassembler::default(),
            stats: CaptureStats::default(),
        }
    }

    fn classic_header(bytes: &mut ByteReader<R>, big: bool, tick_s: f64) -> Result<CaptureFormat> {
        let mut rest = [0u8; 20];
        bytes.read_exact(&mut rest, "pcap file header")?;
        let link = u32_at(&rest, 16, big) & 0x0fff_ffff;
        check_link(bytes.path(), 20, link)?;
        Ok(CaptureFormat::Classic {
            big_endian: big,
            tick_s,
            link,
        })
    }

    /// The format state (to [`PcapReader::resume`] elsewhere).
    pub fn format(&self) -> &CaptureFormat {
        &self.format
    }

    /// What was passed over so far.
    pub fn stats(&self) -> CaptureStats {
        let mut stats = self.stats;
        stats.incomplete = self.reassembler.evicted() + self.reassembler.pending() as u64;
        stats
    }

    /// The next UDP datagram, `None` at the end of the capture.
    pub fn next_datagram(&mut self) -> Result<Option<Datagram<'_>>> {
        let found = loop {
            let Some((record_offset, data_offset, stamp_s, link, start, end)) =
                self.next_record()?
            else {
                return Ok(None);
            };
            self.stats.records += 1;
            if let Some(found) =
                self.parse_frame(record_offset, data_offset, stamp_s, link, start, end)?
            {
                break found;
            }
        };
        let buffer = if found.in_assembled {
            self.reassembler.assembled()
        } else {
            &self.record
        };
        Ok(Some(Datagram {
            record_offset: found.record_offset,
            payload_offset: found.payload_offset,
            stamp_s: found.stamp_s,
            dst_port: found.dst_port,
            payload: &buffer[found.start..found.end],
        }))
    }

    /// Reads the next packet record into `self.record`: `(record offset, file offset of the
    /// packet data, time, link type, data start, data end)`.
    #[allow(clippy::type_complexity)]
    fn next_record(&mut self) -> Result<Option<(u64, u64, f64, u32, usize, usize)>> {
        loop {
            if self.bytes.at_end()? {
                return Ok(None);
            }
            let offset = self.bytes.offset();
            match self.format {
                CaptureFormat::Classic {
                    big_endian,
                    tick_s,
                    link,
                } => {
                    let mut head = [0u8; 16];
                    self.bytes.read_exact(&mut head, "pcap record header")?;
                    let secs = u32_at(&head, 0, big_endian);
                    let frac = u32_at(&head, 4, big_endian);
                    let captured = u32_at(&head, 8, big_endian) as usize;
                    if captured > MAX_RECORD {
                        return Err(self.bytes.error_at(
                            offset + 8,
                            format!("record of {captured} bytes exceeds {MAX_RECORD}"),
                        ));
                    }
                    self.record.resize(captured, 0);
                    self.bytes
                        .read_exact(&mut self.record, "pcap record data")?;
                    let stamp = f64::from(secs) + f64::from(frac) * tick_s;
                    return Ok(Some((offset, offset + 16, stamp, link, 0, captured)));
                }
                CaptureFormat::Ng { big_endian, .. } => {
                    let mut head = [0u8; 8];
                    self.bytes.read_exact(&mut head, "pcapng block header")?;
                    if head[..4] == [0x0a, 0x0d, 0x0d, 0x0a] {
                        self.section_header_after_type(offset, head)?;
                        continue;
                    }
                    let kind = u32_at(&head, 0, big_endian);
                    let body = self.block_body(offset, u32_at(&head, 4, big_endian))?;
                    if let Some(found) = self.ng_block(offset, kind, body)? {
                        return Ok(Some(found));
                    }
                }
            }
        }
    }

    /// Reads a block body (after type and length) and its trailing length; returns its size.
    fn block_body(&mut self, offset: u64, total: u32) -> Result<usize> {
        let total = total as usize;
        if total < 12 || total % 4 != 0 || total > MAX_RECORD {
            return Err(self.bytes.error_at(
                offset + 4,
                format!("pcapng block length {total} is not a multiple of 4 in 12..={MAX_RECORD}"),
            ));
        }
        self.record.resize(total - 8, 0);
        self.bytes.read_exact(&mut self.record, "pcapng block")?;
        Ok(total - 12)
    }

    fn section_header(&mut self, offset: u64) -> Result<()> {
        let mut rest = [0u8; 4];
        self.bytes
            .read_exact(&mut rest, "pcapng section header length")?;
        let mut head = [0u8; 8];
        head[..4].copy_from_slice(&[0x0a, 0x0d, 0x0d, 0x0a]);
        head[4..].copy_from_slice(&rest);
        self.section_header_after_type(offset, head)
    }

    /// A section header block: its byte-order magic sets the endianness of the section.
    fn section_header_after_type(&mut self, offset: u64, head: [u8; 8]) -> Result<()> {
        let mut magic = [0u8; 4];
        self.bytes
            .read_exact(&mut magic, "pcapng byte-order magic")?;
        let big = match magic {
            [0x1a, 0x2b, 0x3c, 0x4d] => true,
            [0x4d, 0x3c, 0x2b, 0x1a] => false,
            _ => {
                return Err(self
                    .bytes
                    .error_at(offset + 8, "pcapng section header: bad byte-order magic"));
            }
        };
        let total = u32_at(&head, 4, big) as usize;
        if total < 28 || total % 4 != 0 || total > MAX_RECORD {
            return Err(self.bytes.error_at(
                offset + 4,
                format!("pcapng section header length {total} is out of range"),
            ));
        }
        self.record.resize(total - 12, 0);
        self.bytes
            .read_exact(&mut self.record, "pcapng section header")?;
        self.format = CaptureFormat::Ng {
            big_endian: big,
            interfaces: Vec::new(),
        };
        Ok(())
    }

    /// Handles one non-section block whose body (length `len`) is in `self.record`.
    #[allow(clippy::type_complexity)]
    fn ng_block(
        &mut self,
        offset: u64,
        kind: u32,
        len: usize,
    ) -> Result<Option<(u64, u64, f64, u32, usize, usize)>> {
        let CaptureFormat::Ng {
            big_endian: big,
            interfaces,
        } = &mut self.format
        else {
            return Ok(None);
        };
        let big = *big;
        let body = &self.record[..len];
        let short = |what: &str| {
            Error::truncated(
                self.bytes.path(),
                Location::Byte(offset + 8),
                what.to_owned(),
            )
        };
        let interface = |interfaces: &[Interface], id: usize| {
            interfaces.get(id).copied().ok_or_else(|| {
                Error::malformed(
                    self.bytes.path(),
                    Location::Byte(offset + 8),
                    format!(
                        "packet of interface {id}, but the section declares {}",
                        interfaces.len()
                    ),
                )
            })
        };
        match kind {
            1 => {
                if len < 8 {
                    return Err(short("pcapng interface description"));
                }
                let link = u32::from(u16_at(body, 0, big));
                check_link(self.bytes.path(), offset + 8, link)?;
                let tick_s = ng_tick(&body[8..], big);
                interfaces.push(Interface { link, tick_s });
                Ok(None)
            }
            6 | 2 => {
                if len < 20 {
                    return Err(short("pcapng packet block"));
                }
                let id = if kind == 6 {
                    u32_at(body, 0, big) as usize
                } else {
                    usize::from(u16_at(body, 0, big))
                };
                let iface = interface(interfaces, id)?;
                let ticks =
                    (u64::from(u32_at(body, 4, big)) << 32) | u64::from(u32_at(body, 8, big));
                let captured = u32_at(body, 12, big) as usize;
                if captured > len - 20 {
                    return Err(Error::malformed(
                        self.bytes.path(),
                        Location::Byte(offset + 20),
                        format!("captured length {captured} exceeds the block"),
                    ));
                }
                let stamp = ticks as f64 * iface.tick_s;
                Ok(Some((
                    offset,
                    offset + 28,
                    stamp,
                    iface.link,
                    20,
                    20 + captured,
                )))
            }
            3 => {
                if len < 4 {
                    return Err(short("pcapng simple packet block"));
                }
                let iface = interface(interfaces, 0)?;
                let original = u32_at(body, 0, big) as usize;
                let captured = original.min(len - 4);
                Ok(Some((
                    offset,
                    offset + 12,
                    f64::NAN,
                    iface.link,
                    4,
                    4 + captured,
                )))
            }
            _ => Ok(None),
        }
    }

    /// Finds the UDP datagram in a link-layer frame at `self.record[start..end]`.
    fn parse_frame(
        &mut self,
        record_offset: u64,
        data_offset: u64,
        stamp_s: f64,
        link: u32,
        start: usize,
        end: usize,
    ) -> Result<Option<Found>> {
        let data = &self.record[start..end];
        let Some((ethertype, ip_at)) = net::link_payload(link, data) else {
            self.stats.not_udp += 1;
            return Ok(None);
        };
        let ip_file = data_offset + ip_at as u64;
        let ip = &data[ip_at..];
        let udp = match ethertype {
            0x0800 => self.ipv4(record_offset, ip_file, stamp_s, start + ip_at, ip.len())?,
            0x86dd => net::ipv6(ip).map(|(at, len)| {
                (
                    false,
                    start + ip_at + at,
                    len,
                    ip_file + at as u64,
                    record_offset,
                    stamp_s,
                )
            }),
            _ => None,
        };
        let Some((in_assembled, udp_at, udp_len, udp_file, record_offset, stamp_s)) = udp else {
            self.stats.not_udp += 1;
            return Ok(None);
        };
        let buffer = if in_assembled {
            self.reassembler.assembled()
        } else {
            &self.record
        };
        let udp = &buffer[udp_at..udp_at + udp_len];
        if udp.len() < 8 {
            return Err(self.truncated_capture(udp_file, 8, udp.len()));
        }
        let claimed = usize::from(u16::from_be_bytes([udp[4], udp[5]]));
        // A length of 0 is a jumbogram or a capture of offloaded segments: take what is there.
        let length = if claimed == 0 { udp.len() } else { claimed };
        if length < 8 {
            return Err(Error::malformed(
                self.bytes.path(),
                Location::Byte(udp_file + 4),
                format!("UDP length {length} is shorter than its header"),
            ));
        }
        if length > udp.len() {
            return Err(self.truncated_capture(udp_file, length, udp.len()));
        }
        Ok(Some(Found {
            record_offset,
            payload_offset: udp_file + 8,
            stamp_s,
            dst_port: u16::from_be_bytes([udp[2], udp[3]]),
            in_assembled,
            start: udp_at + 8,
            end: udp_at + length,
        }))
    }

    fn truncated_capture(&self, at: u64, wanted: usize, got: usize) -> Error {
        Error::malformed(
            self.bytes.path(),
            Location::Byte(at),
            format!(
                "UDP datagram of {wanted} bytes, only {got} captured (capture snap length too \
                 small, or the file is damaged)"
            ),
        )
    }

    /// An IPv4 packet at `self.record[at..at + len]`: `(in assembled buffer, UDP start, UDP
    /// length, UDP file offset, record offset, stamp)`, or `None` when it is not UDP or is an
    /// incomplete fragment.
    #[allow(clippy::type_complexity)]
    fn ipv4(
        &mut self,
        record_offset: u64,
        file: u64,
        stamp_s: f64,
        at: usize,
        len: usize,
    ) -> Result<Option<(bool, usize, usize, u64, u64, f64)>> {
        let ip = &self.record[at..at + len];
        let header = match net::ipv4(ip) {
            Ok(Some(h)) if h.udp => h,
            Ok(_) => return Ok(None),
            Err((offset, reason)) => {
                return Err(Error::malformed(
                    self.bytes.path(),
                    Location::Byte(file + offset as u64),
                    reason,
                ));
            }
        };
        let payload_file = file + header.header as u64;
        if !header.is_fragment() {
            let len = header.end - header.header;
            return Ok(Some((
                false,
                at + header.header,
                len,
                payload_file,
                record_offset,
                stamp_s,
            )));
        }
        if header.total > ip.len() {
            return Err(self.truncated_capture(file, header.total, ip.len()));
        }
        self.stats.fragments += 1;
        let piece = net::Piece {
            key: header.key,
            offset: header.fragment_offset,
            more: header.more_fragments,
            record_offset,
            payload_offset: payload_file,
            stamp_s,
        };
        let data = &ip[header.header..header.end];
        if piece.offset + data.len() > 65_535 {
            return Err(Error::malformed(
                self.bytes.path(),
                Location::Byte(file + 6),
                "IPv4 fragment extends past 65535 bytes",
            ));
        }
        Ok(self.reassembler.add(piece, data).map(|done| {
            self.stats.reassembled += 1;
            (
                true,
                0,
                done.len,
                done.payload_offset,
                done.record_offset,
                done.stamp_s,
            )
        }))
    }
}

/// The pcapng `if_tsresol` option (code 9) of an interface's options: seconds per tick
/// (default microseconds).
fn ng_tick(mut options: &[u8], big: bool) -> f64 {
    while options.len() >= 4 {
        let code = u16_at(options, 0, big);
        let len = usize::from(u16_at(options, 2, big));
        let padded = len.div_ceil(4) * 4;
        if code == 0 || options.len() < 4 + len {
            break;
        }
        if code == 9 && len >= 1 {
            let v = options[4];
            let exponent = i32::from(v & 0x7f);
            return if v & 0x80 == 0 {
                10f64.powi(-exponent)
            } else {
                2f64.powi(-exponent)
            };
        }
        options = &options[(4 + padded).min(options.len())..];
    }
    1e-6
}

/// The link types the reader understands (tcpdump.org `LINKTYPE_*` values).
fn check_link(name: &Path, at: u64, link: u32) -> Result<()> {
    match link {
        0 | 1 | 101 | 113 | 228 | 229 | 276 => Ok(()),
        _ => Err(Error::malformed(
            name,
            Location::Byte(at),
            format!(
                "link type {link} is not supported (Ethernet, Linux cooked capture, loopback or \
                 raw IP are)"
            ),
        )),
    }
}
