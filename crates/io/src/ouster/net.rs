//! The network layers of a captured frame: from the link layer to IP, from IPv4 (fragments
//! reassembled, RFC 791 §3.2) or IPv6 (no extension headers, RFC 8200) to UDP.

/// Largest number of IPv4 datagrams reassembled at the same time; the oldest is dropped
/// (and counted) beyond it.
const MAX_PARTIALS: usize = 64;

/// The network-layer protocol (an ethertype) and where its header starts in a frame of link
/// type `link` (tcpdump.org `LINKTYPE_*`), or `None` for other protocols.
pub(super) fn link_payload(link: u32, data: &[u8]) -> Option<(u16, usize)> {
    let be16 = |at: usize| {
        data.get(at..at + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
    };
    match link {
        // Ethernet, skipping up to two 802.1Q / 802.1ad tags.
        1 => {
            let mut at = 12;
            let mut ethertype = be16(at)?;
            while matches!(ethertype, 0x8100 | 0x88a8 | 0x9100) && at < 20 {
                at += 4;
                ethertype = be16(at)?;
            }
            Some((ethertype, at + 2))
        }
        // BSD loopback: a 4-byte address family in the capturing host's byte order.
        0 => {
            let family = data.get(..4)?;
            let family = u32::from_le_bytes([family[0], family[1], family[2], family[3]]).min(
                u32::from_be_bytes([family[0], family[1], family[2], family[3]]),
            );
            match family {
                2 => Some((0x0800, 4)),
                24 | 28 | 30 => Some((0x86dd, 4)),
                _ => None,
            }
        }
        101 => match data.first()? >> 4 {
            4 => Some((0x0800, 0)),
            6 => Some((0x86dd, 0)),
            _ => None,
        },
        228 => Some((0x0800, 0)),
        229 => Some((0x86dd, 0)),
        // Linux cooked capture v1 (protocol at byte 14 of 16) and v2 (at byte 0 of 20).
        113 => Some((be16(14)?, 16)),
        276 => Some((be16(0)?, 20)),
        _ => None,
    }
    .filter(|&(_, at)| at <= data.len())
}

/// A UDP datagram in an IPv6 packet without extension headers: `(UDP start, length)`.
pub(super) fn ipv6(ip: &[u8]) -> Option<(usize, usize)> {
    if ip.len() < 40 || ip[0] >> 4 != 6 || ip[6] != 17 {
        return None;
    }
    let payload = usize::from(u16::from_be_bytes([ip[4], ip[5]]));
    let available = ip.len() - 40;
    Some((
        40,
        if payload == 0 {
            available
        } else {
            payload.min(available)
        },
    ))
}

/// The fields of an IPv4 header the reader needs.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ipv4Header {
    /// Header length, bytes.
    pub header: usize,
    /// Total length from the header (0: unknown, as in captures of offloaded segments).
    pub total: usize,
    /// End of the packet in the captured bytes (the total length, or what was captured).
    pub end: usize,
    /// True for UDP.
    pub udp: bool,
    /// The "more fragments" flag.
    pub more_fragments: bool,
    /// Fragment offset, bytes.
    pub fragment_offset: usize,
    /// Source, destination, identification, protocol: what identifies a datagram's fragments.
    pub key: (u32, u32, u16, u8),
}

impl Ipv4Header {
    /// True when the packet is a fragment of a larger datagram.
    pub fn is_fragment(&self) -> bool {
        self.more_fragments || self.fragment_offset > 0
    }
}

/// Parses an IPv4 header; `None` when `ip` is not IPv4, `Err((offset, reason))` when the
/// header is inconsistent.
pub(super) fn ipv4(ip: &[u8]) -> Result<Option<Ipv4Header>, (usize, String)> {
    if ip.len() < 20 || ip[0] >> 4 != 4 {
        return Ok(None);
    }
    let header = usize::from(ip[0] & 0x0f) * 4;
    let total = usize::from(u16::from_be_bytes([ip[2], ip[3]]));
    if header < 20 || header > ip.len() {
        return Err((0, format!("IPv4 header length {header} is out of range")));
    }
    if total != 0 && total < header {
        return Err((
            2,
            format!("IPv4 total length {total} is shorter than its header"),
        ));
    }
    // Total length 0: a capture of a segmentation-offloaded packet; take what is there.
    // Shorter data than the total: the capture was cut. Longer: Ethernet padding.
    let end = if total == 0 {
        ip.len()
    } else {
        total.min(ip.len())
    };
    let flags = u16::from_be_bytes([ip[6], ip[7]]);
    Ok(Some(Ipv4Header {
        header,
        total,
        end,
        udp: ip[9] == 17,
        more_fragments: flags & 0x2000 != 0,
        fragment_offset: usize::from(flags & 0x1fff) * 8,
        key: (
            u32::from_be_bytes([ip[12], ip[13], ip[14], ip[15]]),
            u32::from_be_bytes([ip[16], ip[17], ip[18], ip[19]]),
            u16::from_be_bytes([ip[4], ip[5]]),
            ip[9],
        ),
    }))
}

/// One fragment's place, and where it came from in the file.
pub(super) struct Piece {
    pub key: (u32, u32, u16, u8),
    pub offset: usize,
    pub more: bool,
    pub record_offset: u64,
    pub payload_offset: u64,
    pub stamp_s: f64,
}

/// A datagram whose fragments all arrived: its bytes are [`Reassembler::assembled`].
pub(super) struct Completed {
    /// The capture record of the first fragment.
    pub record_offset: u64,
    /// The file offset of the first fragment's payload.
    pub payload_offset: u64,
    /// The first fragment's capture time.
    pub stamp_s: f64,
    /// Length of the IP payload.
    pub len: usize,
}

struct Partial {
    first: Piece,
    total: Option<usize>,
    pieces: Vec<(usize, Vec<u8>)>,
}

/// Collects IPv4 fragments until their datagram is complete.
#[derive(Default)]
pub(super) struct Reassembler {
    partials: Vec<Partial>,
    assembled: Vec<u8>,
    evicted: u64,
}

impl Reassembler {
    /// Adds a fragment with its payload `data`; returns the datagram it completes.
    pub fn add(&mut self, piece: Piece, data: &[u8]) -> Option<Completed> {
        let index = match self.partials.iter().position(|p| p.first.key == piece.key) {
            Some(i) => i,
            None => {
                if self.partials.len() == MAX_PARTIALS {
                    self.partials.remove(0);
                    self.evicted += 1;
                }
                self.partials.push(Partial {
                    first: Piece { ..piece },
                    total: None,
                    pieces: Vec::new(),
                });
                self.partials.len() - 1
            }
        };
        let partial = &mut self.partials[index];
        if !piece.more {
            partial.total = Some(piece.offset + data.len());
        }
        partial.pieces.push((piece.offset, data.to_vec()));
        if piece.offset == 0 {
            partial.first = piece;
        }
        let total = partial.total?;
        partial.pieces.sort_by_key(|(offset, _)| *offset);
        let mut covered = 0;
        for (offset, bytes) in &partial.pieces {
            if *offset > covered {
                return None;
            }
            covered = covered.max(offset + bytes.len());
        }
        if covered < total {
            return None;
        }
        let partial = self.partials.remove(index);
        self.assembled.clear();
        self.assembled.resize(total, 0);
        for (offset, bytes) in &partial.pieces {
            let end = (offset + bytes.len()).min(total);
            if *offset < end {
                self.assembled[*offset..end].copy_from_slice(&bytes[..end - offset]);
            }
        }
        Some(Completed {
            record_offset: partial.first.record_offset,
            payload_offset: partial.first.payload_offset,
            stamp_s: partial.first.stamp_s,
            len: total,
        })
    }

    /// The last completed datagram's IP payload.
    pub fn assembled(&self) -> &[u8] {
        &self.assembled
    }

    /// Datagrams waiting for fragments.
    pub fn pending(&self) -> usize {
        self.partials.len()
    }

    /// Datagrams dropped incomplete to make room.
    pub fn evicted(&self) -> u64 {
        self.evicted
    }
}
