//! Chunks of every compression decode to their records: whole, lazily, cut short; bad ones
//! are errors.
#![allow(clippy::unwrap_used)]

use std::io::Write;

use super::*;

/// Message records (`[opcode][u64 length][body]`) of varied sizes, about 300 kB.
fn records() -> Vec<u8> {
    let mut out = Vec::new();
    let mut x = 12345u32;
    for k in 0..120usize {
        let len = 22 + (k * 977) % 5000;
        out.push(0x05);
        out.extend_from_slice(&(len as u64).to_le_bytes());
        for _ in 0..len {
            // Half predictable, half noise: something to compress.
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
            out.push(if x % 3 == 0 { (x >> 16) as u8 } else { k as u8 });
        }
    }
    out
}

fn compress(name: &str, data: &[u8]) -> Vec<u8> {
    match name {
        "zstd" => zstd::bulk::compress(data, 3).unwrap(),
        "lz4" => {
            let mut e = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
            e.write_all(data).unwrap();
            let (out, result) = e.finish();
            result.unwrap();
            out
        }
        _ => data.to_vec(),
    }
}

fn crc(data: &[u8]) -> u32 {
    let mut c = flate2::Crc::new();
    c.update(data);
    c.sum()
}

/// A chunk record (opcode and length included) claiming `size` uncompressed bytes.
fn chunk(name: &str, records: &[u8], size: u64, crc: u32) -> Vec<u8> {
    let data = compress(name, records);
    let mut body = Vec::new();
    body.extend_from_slice(&1u64.to_le_bytes());
    body.extend_from_slice(&2u64.to_le_bytes());
    body.extend_from_slice(&size.to_le_bytes());
    body.extend_from_slice(&crc.to_le_bytes());
    body.extend_from_slice(&(name.len() as u32).to_le_bytes());
    body.extend_from_slice(name.as_bytes());
    body.extend_from_slice(&(data.len() as u64).to_le_bytes());
    body.extend_from_slice(&data);
    let mut record = vec![0x06];
    record.extend_from_slice(&(body.len() as u64).to_le_bytes());
    record.extend_from_slice(&body);
    record
}

fn decoded(c: &ChunkBuf) -> &[u8] {
    c.bytes(c.pos, c.end())
}

#[test]
fn whole_chunks_decode_to_their_records() {
    let records = records();
    let mut c = ChunkBuf::default();
    for name in ["", "zstd", "lz4"] {
        for sum in [0, crc(&records)] {
            let mut record = chunk(name, &records, records.len() as u64, sum);
            c.load(&mut record, true, false).unwrap();
            assert_eq!(decoded(&c), &records[..], "{name:?}");
            assert_eq!(c.compression_name(), name);
            // Lazily, in steps: the same bytes.
            let mut record = chunk(name, &records, records.len() as u64, sum);
            c.load(&mut record, true, true).unwrap();
            let mut upto = c.pos + 1000;
            while upto < c.end() {
                assert!(c.fill(upto).unwrap());
                assert_eq!(c.bytes(c.pos, upto), &records[..upto - c.pos]);
                upto += 77_777;
            }
            assert!(c.fill(c.end()).unwrap());
            assert_eq!(decoded(&c), &records[..], "{name:?} lazily");
        }
    }
}

#[test]
fn lazy_chunks_decode_only_what_is_asked() {
    let records = records();
    let mut c = ChunkBuf::default();
    for name in ["zstd", "lz4"] {
        let mut record = chunk(name, &records, records.len() as u64, crc(&records));
        c.load(&mut record, true, true).unwrap();
        assert!(c.fill(100).unwrap());
        assert_eq!(c.bytes(0, 100), &records[..100]);
        assert!(
            c.filled < records.len() / 2,
            "{name}: {} of {} bytes decoded for 100",
            c.filled,
            records.len()
        );
    }
}

#[test]
fn bad_chunks_are_errors() {
    let records = records();
    let n = records.len() as u64;
    let mut c = ChunkBuf::default();
    for name in ["zstd", "lz4"] {
        for lazy in [false, true] {
            let mut bad_crc = chunk(name, &records, n, crc(&records) ^ 1);
            let e = c
                .load(&mut bad_crc, true, lazy)
                .and_then(|()| c.fill(c.end()).map(|_| ()))
                .unwrap_err();
            assert!(e.contains("CRC"), "{e}");
            for size in [n - 1, n + 1, 1 << 31] {
                let mut bad_size = chunk(name, &records, size, 0);
                let e = c
                    .load(&mut bad_size, true, lazy)
                    .and_then(|()| c.fill(c.end()).map(|_| ()))
                    .unwrap_err();
                assert!(e.contains("bytes"), "{name} {lazy} {size}: {e}");
            }
        }
    }
    let mut unknown = chunk("bz2", &records, n, 0);
    let e = c.load(&mut unknown, true, false).unwrap_err();
    assert!(e.contains("bz2"), "{e}");
    let mut huge = chunk("zstd", &records, 1 << 40, 0);
    assert!(c.load(&mut huge, true, false).is_err());
    // Whole records but a header cut short, or records longer than the chunk.
    let whole = chunk("", &records, n, 0);
    let mut cut = whole[..RECORD_HEAD + 30].to_vec();
    assert!(c.load(&mut cut, true, false).is_err());
    let mut short = whole[..whole.len() - 1].to_vec();
    assert!(c.load(&mut short, true, false).is_err());
}

#[test]
fn cut_chunks_give_what_is_there() {
    let records = records();
    let mut c = ChunkBuf::default();
    for name in ["", "zstd", "lz4"] {
        let whole = chunk(name, &records, records.len() as u64, crc(&records));
        for keep in [RECORD_HEAD + 10, whole.len() / 3, whole.len() * 9 / 10] {
            let mut cut = whole[..keep].to_vec();
            c.load(&mut cut, false, false).unwrap();
            let got = decoded(&c);
            assert!(got.len() < records.len(), "{name} {keep}");
            assert_eq!(got, &records[..got.len()], "{name} {keep}");
            if keep > whole.len() / 2 {
                assert!(got.len() > records.len() / 4, "{name}: {} bytes", got.len());
            }
        }
    }
}

fn lz4_with(records: &[u8], block: lz4::BlockSize, mode: lz4::BlockMode, sums: bool) -> Vec<u8> {
    let checksum = |on| {
        if on {
            lz4::ContentChecksum::ChecksumEnabled
        } else {
            lz4::ContentChecksum::NoChecksum
        }
    };
    let mut e = lz4::EncoderBuilder::new()
        .block_size(block)
        .block_mode(mode)
        .block_checksum(if sums {
            lz4::liblz4::BlockChecksum::BlockChecksumEnabled
        } else {
            lz4::liblz4::BlockChecksum::NoBlockChecksum
        })
        .checksum(checksum(sums))
        .build(Vec::new())
        .unwrap();
    e.write_all(records).unwrap();
    let (out, result) = e.finish();
    result.unwrap();
    out
}

/// `chunk` with ready-compressed data.
fn chunk_of(name: &str, data: &[u8], size: u64, crc: u32) -> Vec<u8> {
    let mut record = chunk("", data, size, crc);
    // Same layout; only the compression name differs.
    let mut body = record.split_off(RECORD_HEAD);
    body.splice(NAME_AT - 4..NAME_AT, (name.len() as u32).to_le_bytes());
    body.splice(NAME_AT..NAME_AT, name.bytes());
    record.truncate(1);
    record.extend_from_slice(&(body.len() as u64).to_le_bytes());
    record.extend_from_slice(&body);
    record
}

#[test]
fn lz4_frames_of_every_layout() {
    use lz4::{BlockMode, BlockSize};
    let records = records();
    let n = records.len() as u64;
    let mut c = ChunkBuf::default();
    for block in [
        BlockSize::Max64KB,
        BlockSize::Max256KB,
        BlockSize::Max1MB,
        BlockSize::Max4MB,
    ] {
        for mode in [BlockMode::Linked, BlockMode::Independent] {
            for sums in [false, true] {
                let data = lz4_with(&records, block.clone(), mode.clone(), sums);
                for (crc, lazy) in [(0, false), (crc(&records), false), (0, true)] {
                    let mut record = chunk_of("lz4", &data, n, crc);
                    c.load(&mut record, true, lazy).unwrap();
                    assert!(c.fill(c.end()).unwrap());
                    assert_eq!(decoded(&c), &records[..]);
                }
                // Two frames in one chunk read as one stream.
                let mut two = data.clone();
                two.extend_from_slice(&data);
                let mut twice = records.clone();
                twice.extend_from_slice(&records);
                let mut record = chunk_of("lz4", &two, 2 * n, 0);
                c.load(&mut record, true, false).unwrap();
                assert_eq!(decoded(&c), &twice[..]);
            }
        }
    }
}

#[test]
fn lz4_checksums_are_checked_without_a_crc() {
    let records = records();
    let n = records.len() as u64;
    let data = lz4_with(
        &records,
        lz4::BlockSize::Max64KB,
        lz4::BlockMode::Linked,
        true,
    );
    let mut c = ChunkBuf::default();
    for at in [data.len() / 3, data.len() / 2] {
        let mut bad = data.clone();
        bad[at] ^= 0x20;
        for crc in [0, crc(&records)] {
            let mut record = chunk_of("lz4", &bad, n, crc);
            assert!(c.load(&mut record, true, false).is_err(), "{at} {crc}");
        }
    }
    // A bad content checksum over good records: an error unless the chunk's CRC vouches for
    // them.
    let mut bad = data.clone();
    let last = bad.len() - 1;
    bad[last] ^= 1;
    let mut record = chunk_of("lz4", &bad, n, 0);
    let e = c.load(&mut record, true, false).unwrap_err();
    assert!(e.contains("checksum"), "{e}");
    let mut record = chunk_of("lz4", &bad, n, crc(&records));
    c.load(&mut record, true, false).unwrap();
    assert_eq!(decoded(&c), &records[..]);
}

#[test]
fn xxh32_known_answers() {
    assert_eq!(lz4_frame::xxh32(b""), 0x02CC_5D05);
    assert_eq!(lz4_frame::xxh32(b"abc"), 0x32D1_53FF);
}
