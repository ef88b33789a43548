//! Packet captures: Ethernet frames of UDP datagrams (IPv4, optionally fragmented and
//! VLAN-tagged) in classic pcap or pcapng files.

/// A UDP datagram (header and `payload`) from port 7502 to `port`, checksum left 0.
pub fn udp_datagram(payload: &[u8], port: u16) -> Vec<u8> {
    let mut udp = Vec::with_capacity(payload.len() + 8);
    udp.extend_from_slice(&7502u16.to_be_bytes());
    udp.extend_from_slice(&port.to_be_bytes());
    udp.extend_from_slice(&((payload.len() + 8) as u16).to_be_bytes());
    udp.extend_from_slice(&[0, 0]);
    udp.extend_from_slice(payload);
    udp
}

/// Ethernet frames (with an 802.1Q tag when `vlan`) carrying one UDP datagram to `port` in
/// IPv4 packets of id `id`, fragmented to at most `mtu_payload` bytes of IP payload per
/// frame (a multiple of 8; `usize::MAX` for one frame).
pub fn udp_frames(
    payload: &[u8],
    port: u16,
    id: u16,
    mtu_payload: usize,
    vlan: bool,
) -> Vec<Vec<u8>> {
    ip_frames(&udp_datagram(payload, port), id, mtu_payload, vlan)
}

/// Ethernet frames carrying IPv4 packets of `ip_payload` with id `id`, fragmented so that
/// each fragment carries at most `mtu_payload` bytes (a multiple of 8).
pub fn ip_frames(ip_payload: &[u8], id: u16, mtu_payload: usize, vlan: bool) -> Vec<Vec<u8>> {
    let mut frames = Vec::new();
    let mut offset = 0usize;
    loop {
        let end = ip_payload.len().min(offset.saturating_add(mtu_payload));
        let more = end < ip_payload.len();
        let mut f = vec![0u8; 12];
        if vlan {
            f.extend_from_slice(&[0x81, 0x00, 0x00, 0x05]);
        }
        f.extend_from_slice(&[0x08, 0x00, 0x45, 0]);
        f.extend_from_slice(&((20 + end - offset) as u16).to_be_bytes());
        f.extend_from_slice(&id.to_be_bytes());
        f.extend_from_slice(&((offset / 8) as u16 | if more { 0x2000 } else { 0 }).to_be_bytes());
        f.extend_from_slice(&[64, 17, 0, 0, 10, 5, 5, 1, 10, 5, 5, 2]);
        f.extend_from_slice(&ip_payload[offset..end]);
        frames.push(f);
        offset = end;
        if !more {
            return frames;
        }
    }
}

/// A classic pcap of Ethernet frames, microsecond or nanosecond stamps, either byte order.
pub fn classic_pcap(frames: &[Vec<u8>], big: bool, nanos: bool) -> Vec<u8> {
    let w32 = |v: u32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let w16 = |v: u16| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut b = Vec::new();
    b.extend_from_slice(&w32(if nanos { 0xa1b2_3c4d } else { 0xa1b2_c3d4 }));
    b.extend_from_slice(&w16(2));
    b.extend_from_slice(&w16(4));
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&w32(65535));
    b.extend_from_slice(&w32(1));
    for (k, f) in frames.iter().enumerate() {
        b.extend_from_slice(&w32(1_700_000_000 + k as u32));
        b.extend_from_slice(&w32(500));
        b.extend_from_slice(&w32(f.len() as u32));
        b.extend_from_slice(&w32(f.len() as u32));
        b.extend_from_slice(f);
    }
    b
}

/// A little-endian pcapng: section header, one Ethernet interface with nanosecond
/// resolution, a name-resolution block to skip, and one enhanced packet block per frame.
pub fn pcapng(frames: &[Vec<u8>]) -> Vec<u8> {
    let block = |kind: u32, body: &[u8]| {
        let mut body = body.to_vec();
        while body.len() % 4 != 0 {
            body.push(0);
        }
        let total = (body.len() + 12) as u32;
        let mut b = kind.to_le_bytes().to_vec();
        b.extend_from_slice(&total.to_le_bytes());
        b.extend_from_slice(&body);
        b.extend_from_slice(&total.to_le_bytes());
        b
    };
    let mut shb = 0x1a2b_3c4du32.to_le_bytes().to_vec();
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&u64::MAX.to_le_bytes());
    let mut out = block(0x0a0d_0d0a, &shb);
    // Interface: Ethernet, snap length 0, option if_tsresol = 9 (nanoseconds).
    let mut idb = vec![1, 0, 0, 0];
    idb.extend_from_slice(&0u32.to_le_bytes());
    idb.extend_from_slice(&[9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0]);
    out.extend(block(1, &idb));
    out.extend(block(4, &[0, 0, 0, 0]));
    for (k, f) in frames.iter().enumerate() {
        let ns = 1_700_000_000_000_000_000u64 + k as u64;
        let mut epb = 0u32.to_le_bytes().to_vec();
        epb.extend_from_slice(&((ns >> 32) as u32).to_le_bytes());
        epb.extend_from_slice(&(ns as u32).to_le_bytes());
        epb.extend_from_slice(&(f.len() as u32).to_le_bytes());
        epb.extend_from_slice(&(f.len() as u32).to_le_bytes());
        epb.extend_from_slice(f);
        out.extend(block(6, &epb));
    }
    out
}
