//! The mutator: a seeded stream of edits turning a valid seed input into a mutated one.
//!
//! Every case draws from its own generator, seeded from `(seed, reader, case)`, so a case can
//! be regenerated alone (`--case`) and the same seed always gives the same inputs, in any
//! order and on any number of threads.

use raypath_geometry::testing::workloads::SplitMix64;

/// Tokens every reader gets: numbers that stress parsing and counts, separators, bytes that
/// are not UTF-8.
pub const COMMON_TOKENS: &[&[u8]] = &[
    b"0",
    b"-0",
    b"1",
    b"-1",
    b"nan",
    b"NaN",
    b"inf",
    b"-inf",
    b"1e308",
    b"-1e308",
    b"1e-320",
    b"1e400",
    b"255",
    b"65536",
    b"2147483648",
    b"4294967295",
    b"4294967296",
    b"18446744073709551615",
    b"99999999999999999999999",
    b"0x10",
    b"+",
    b" ",
    b"\t",
    b"\n",
    b"\r\n",
    b",",
    b"#",
    b"\"",
    b"\0",
    b"\xff\xfe",
    b"\xc3\xa9",
    b"\xe2\x82",
];

/// Bytes worth writing over one byte: boundaries, ASCII structure, high bits.
const INTERESTING_BYTES: [u8; 22] = [
    0, 1, 2, 0x7f, 0x80, 0x81, 0xfe, 0xff, 0x10, 0x20, 0x40, b'\n', b'\r', b' ', b'0', b'9', b'-',
    b'.', b'e', b'n', b',', b'#',
];

/// Numbers worth writing over a 2-, 4- or 8-byte field (lengths, counts, offsets).
const INTERESTING_INTS: [u64; 18] = [
    0,
    1,
    2,
    3,
    7,
    8,
    16,
    0x7f,
    0xff,
    0x100,
    0x7fff,
    0x8000,
    0xffff,
    0x1_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fffe,
    0xffff_ffff,
];

/// A uniform draw from `0..n` (`n > 0`).
pub fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// FNV-1a of a name: the reader's part of a case's seed.
pub fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The generator of case `case` of `reader` in a run seeded with `seed`.
pub fn case_rng(seed: u64, reader: &str, case: u64) -> SplitMix64 {
    let mut mix = SplitMix64::new(seed ^ fnv1a(reader).rotate_left(29));
    let base = mix.next_u64();
    let mut rng = SplitMix64::new(base ^ case.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    rng.next_u64();
    rng
}

/// One mutated input: the seed it came from, its bytes and free random bits for the reader
/// (options such as a look-ahead or a label source).
pub struct Mutated {
    /// Index of the seed in the reader's seeds.
    pub seed: usize,
    /// The input.
    pub bytes: Vec<u8>,
    /// Random bits the reader may use to pick options.
    pub variant: u64,
}

/// Mutates one of `seeds` with 1 to 8 edits (mostly one or two) drawn from `rng`.
pub fn mutate(rng: &mut SplitMix64, seeds: &[Vec<u8>], tokens: &[&[u8]]) -> Mutated {
    let seed = below(rng, seeds.len());
    let variant = rng.next_u64();
    let mut bytes = seeds[seed].clone();
    let cap = 2 * seeds.iter().map(Vec::len).max().unwrap_or(0) + 4096;
    let edits = match below(rng, 16) {
        0..=7 => 1,
        8..=11 => 2,
        12..=13 => 3,
        _ => 4 + below(rng, 5),
    };
    for _ in 0..edits {
        edit(rng, &mut bytes, seeds, tokens);
        bytes.truncate(cap);
    }
    Mutated {
        seed,
        bytes,
        variant,
    }
}

/// A random position in `0..=len` (inserting) or `0..len` (overwriting, `len > 0`).
fn position(rng: &mut SplitMix64, len: usize, inclusive: bool) -> usize {
    below(rng, len + usize::from(inclusive))
}

/// A chunk length: short most of the time, now and then long.
fn chunk_len(rng: &mut SplitMix64, len: usize) -> usize {
    let max = if below(rng, 4) == 0 { len } else { 32 };
    1 + below(rng, max.clamp(1, len.max(1)))
}

fn edit(rng: &mut SplitMix64, bytes: &mut Vec<u8>, seeds: &[Vec<u8>], tokens: &[&[u8]]) {
    let len = bytes.len();
    // Edits that need a byte to work on fall back to an insertion on empty input.
    let op = if len == 0 { 7 } else { below(rng, 14) };
    match op {
        // Flip one bit.
        0 => {
            let i = position(rng, len, false);
            bytes[i] ^= 1 << below(rng, 8);
        }
        // Replace a byte with an interesting value …
        1 => {
            let i = position(rng, len, false);
            bytes[i] = INTERESTING_BYTES[below(rng, INTERESTING_BYTES.len())];
        }
        // … or a random one.
        2 => {
            let i = position(rng, len, false);
            bytes[i] = rng.next_u64() as u8;
        }
        // Overwrite a 2-, 4- or 8-byte field with an interesting number (either byte order,
        // sometimes negated, sometimes the input's own length).
        3 => {
            let width = [2usize, 4, 4, 8][below(rng, 4)];
            let mut value = if below(rng, 8) == 0 {
                (len + below(rng, 3)) as u64
            } else {
                INTERESTING_INTS[below(rng, INTERESTING_INTS.len())]
            };
            if below(rng, 6) == 0 {
                value = value.wrapping_neg();
            }
            let le = value.to_le_bytes();
            let field: Vec<u8> = if below(rng, 2) == 0 {
                le[..width].to_vec()
            } else {
                le[..width].iter().rev().copied().collect()
            };
            let i = position(rng, len, false);
            let end = (i + width).min(len);
            bytes[i..end].copy_from_slice(&field[..end - i]);
        }
        // Add or subtract a little from a byte or a 32-bit little-endian field.
        4 => {
            let delta = 1 + below(rng, 16) as u32;
            let i = position(rng, len, false);
            if i + 4 <= len && below(rng, 2) == 0 {
                let mut v = [0u8; 4];
                v.copy_from_slice(&bytes[i..i + 4]);
                let v = u32::from_le_bytes(v);
                let v = if below(rng, 2) == 0 {
                    v.wrapping_add(delta)
                } else {
                    v.wrapping_sub(delta)
                };
                bytes[i..i + 4].copy_from_slice(&v.to_le_bytes());
            } else if below(rng, 2) == 0 {
                bytes[i] = bytes[i].wrapping_add(delta as u8);
            } else {
                bytes[i] = bytes[i].wrapping_sub(delta as u8);
            }
        }
        // Truncate at a random point (twice as likely: cut files are the common case).
        5 | 6 => {
            let at = position(rng, len, false);
            bytes.truncate(at);
        }
        // Insert 1 to 16 random bytes.
        7 => {
            let at = position(rng, len, true);
            let n = 1 + below(rng, 16);
            let insert: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            bytes.splice(at..at, insert);
        }
        // Delete a chunk.
        8 => {
            let n = chunk_len(rng, len);
            let at = position(rng, len - n + 1, false);
            bytes.drain(at..at + n);
        }
        // Duplicate a chunk somewhere.
        9 => {
            let n = chunk_len(rng, len);
            let from = position(rng, len - n + 1, false);
            let chunk = bytes[from..from + n].to_vec();
            let at = position(rng, len, true);
            bytes.splice(at..at, chunk);
        }
        // Overwrite with a token.
        10 => {
            let token = tokens[below(rng, tokens.len())];
            let i = position(rng, len, false);
            let end = (i + token.len()).min(len);
            bytes[i..end].copy_from_slice(&token[..end - i]);
        }
        // Insert a token.
        11 => {
            let token = tokens[below(rng, tokens.len())];
            let at = position(rng, len, true);
            bytes.splice(at..at, token.iter().copied());
        }
        // Replace the word (bytes between separators) around a position with a token.
        12 => {
            let token = tokens[below(rng, tokens.len())];
            let i = position(rng, len, false);
            let separator = |b: u8| matches!(b, b' ' | b'\t' | b'\n' | b'\r' | b',' | b':');
            let mut start = i;
            while start > 0 && i - start < 64 && !separator(bytes[start - 1]) {
                start -= 1;
            }
            let mut end = i;
            while end < len && end - i < 64 && !separator(bytes[end]) {
                end += 1;
            }
            bytes.splice(start..end, token.iter().copied());
        }
        // Splice: this input's head with another seed's tail.
        _ => {
            let other = &seeds[below(rng, seeds.len())];
            let at = position(rng, len, true);
            let from = position(rng, other.len(), true);
            bytes.truncate(at);
            bytes.extend_from_slice(&other[from..]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_inputs() {
        let seeds = vec![b"FLASER 3 1.0 2.0 3.0\n".to_vec(), vec![0u8; 40]];
        let draw = |seed: u64, case: u64| {
            let mut rng = case_rng(seed, "carmen", case);
            mutate(&mut rng, &seeds, COMMON_TOKENS).bytes
        };
        for case in 0..200 {
            assert_eq!(draw(7, case), draw(7, case));
        }
        let differ = (0..200).filter(|&c| draw(7, c) != draw(8, c)).count();
        assert!(differ > 150, "{differ}");
        // Different readers draw different inputs from one seed.
        let mut a = case_rng(7, "carmen", 0);
        let mut b = case_rng(7, "pcd", 0);
        assert_ne!(a.next_u64(), b.next_u64());
    }

    #[test]
    fn mutations_stay_bounded_and_handle_empty_seeds() {
        let seeds = vec![Vec::new(), b"x".to_vec()];
        for case in 0..2000 {
            let mut rng = case_rng(1, "empty", case);
            let m = mutate(&mut rng, &seeds, COMMON_TOKENS);
            assert!(m.bytes.len() <= 2 + 4096);
        }
    }
}
