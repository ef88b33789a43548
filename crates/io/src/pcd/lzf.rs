//! LZF compression, the codec of PCD `binary_compressed` data.
//!
//! LZF (Marc Lehmann's liblzf, <http://oldhome.schmorp.de/marc/liblzf.html>) is a byte-oriented
//! LZ77 variant. A compressed stream is a sequence of tokens, each starting with a control byte
//! `c`:
//!
//! * `c < 32`: a **literal run** — the next `c + 1` bytes are copied to the output.
//! * `c ≥ 32`: a **back reference** — `len = c >> 5`; when `len == 7` the next byte is added to
//!   it; then one byte `b` gives the distance `d = ((c & 0x1f) << 8 | b) + 1`. The decoder copies
//!   `len + 2` bytes starting `d` bytes behind the end of the output, one byte at a time (so a
//!   reference may overlap the bytes it produces, which encodes runs).
//!
//! So a literal run holds 1–32 bytes, a reference 3–264 bytes at a distance of 1–8192 bytes.
//! The stream carries no length: the PCD header stores the uncompressed size, and
//! [`decompress`] checks that the output has exactly that size.
//!
//! This is our own implementation in safe Rust (the existing crates are either thin bindings or
//! young single-author ports, and the PCD reader must never panic on corrupt input and must
//! report the byte offset of a problem). The encoder is a greedy matcher with a 16 Ki-entry hash
//! table of 3-byte prefixes; its output is valid LZF that liblzf (and so PCL) decodes, though not
//! byte-identical to liblzf's.

use std::fmt;

/// Largest distance of a back reference.
const MAX_DISTANCE: usize = 1 << 13;
/// Longest back reference.
const MAX_MATCH: usize = 264;
/// Longest literal run.
const MAX_LITERAL: usize = 32;
const HASH_BITS: u32 = 14;

/// Why an LZF stream could not be decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LzfError {
    /// Byte offset in the compressed input of the token that failed.
    pub offset: usize,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for LzfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "LZF data byte {}: {}", self.offset, self.reason)
    }
}

impl std::error::Error for LzfError {}

/// The largest output [`compress`] can produce for `n` input bytes (one control byte per 32
/// literals, plus one).
pub fn max_compressed_len(n: usize) -> usize {
    n + n / MAX_LITERAL + 1
}

/// Decodes an LZF stream that must expand to exactly `expected_len` bytes.
///
/// Fails (never panics) on a truncated token, a reference before the start of the output, or an
/// output longer or shorter than `expected_len`. The output is allocated once, so
/// `expected_len` must have been checked against a sane limit by the caller.
pub fn decompress(input: &[u8], expected_len: usize) -> Result<Vec<u8>, LzfError> {
    let mut out = Vec::with_capacity(expected_len);
    let mut pos = 0usize;
    let error = |offset: usize, reason: String| LzfError { offset, reason };
    while let Some(&control) = input.get(pos) {
        let token = pos;
        pos += 1;
        if control < 32 {
            let n = usize::from(control) + 1;
            let literal = input
                .get(pos..pos + n)
                .ok_or_else(|| error(token, format!("literal run of {n} bytes is cut off")))?;
            if out.len() + n > expected_len {
                return Err(error(token, overflow(expected_len)));
            }
            out.extend_from_slice(literal);
            pos += n;
        } else {
            let mut len = usize::from(control >> 5);
            if len == 7 {
                let extra = *input
                    .get(pos)
                    .ok_or_else(|| error(token, "back reference is cut off".into()))?;
                len += usize::from(extra);
                pos += 1;
            }
            let low = *input
                .get(pos)
                .ok_or_else(|| error(token, "back reference is cut off".into()))?;
            pos += 1;
            let distance = (usize::from(control & 0x1f) << 8 | usize::from(low)) + 1;
            let n = len + 2;
            let Some(start) = out.len().checked_sub(distance) else {
                return Err(error(
                    token,
                    format!(
                        "back reference {distance} bytes behind reaches before the start \
                         (only {} bytes decoded)",
                        out.len()
                    ),
                ));
            };
            if out.len() + n > expected_len {
                return Err(error(token, overflow(expected_len)));
            }
            for i in start..start + n {
                // `i < out.len()` always holds: `start + distance == out.len()` at the start
                // and the output grows by one byte per step.
                let byte = out.get(i).copied().unwrap_or_default();
                out.push(byte);
            }
        }
    }
    if out.len() != expected_len {
        return Err(error(
            input.len(),
            format!(
                "data expands to {} bytes, the header says {expected_len}",
                out.len()
            ),
        ));
    }
    Ok(out)
}

fn overflow(expected_len: usize) -> String {
    format!("data expands beyond the {expected_len} bytes the header announces")
}

/// Compresses `input` into an LZF stream of at most [`max_compressed_len`] bytes.
pub fn compress(input: &[u8]) -> Vec<u8> {
    let n = input.len();
    let mut out = Vec::with_capacity(max_compressed_len(n).min(n / 2 + 64));
    // Positions + 1 of the last occurrence of each hashed 3-byte prefix (0 = none).
    let mut table = vec![0usize; 1 << HASH_BITS];
    let mut literal_start = 0usize;
    let mut i = 0usize;
    while i + 2 < n {
        let h = hash3(input, i);
        let candidate = table.get(h).copied().unwrap_or(0);
        set(&mut table, h, i + 1);
        if let Some(len) = match_len(input, candidate, i) {
            flush_literals(&mut out, &input[literal_start..i]);
            let distance = i - (candidate - 1) - 1;
            let coded = len - 2;
            let high = (distance >> 8) as u8;
            if coded < 7 {
                out.push(((coded as u8) << 5) | high);
            } else {
                out.push((7 << 5) | high);
                out.push((coded - 7) as u8);
            }
            out.push((distance & 0xff) as u8);
            // Index the positions inside the match so later data can refer to them.
            for j in i + 1..(i + len).min(n.saturating_sub(2)) {
                let h = hash3(input, j);
                set(&mut table, h, j + 1);
            }
            i += len;
            literal_start = i;
        } else {
            i += 1;
        }
    }
    flush_literals(&mut out, &input[literal_start..]);
    out
}

/// The length of the match between the data at `candidate - 1` (1-based, 0 = none) and at `i`,
/// when it is usable (≥ 3 bytes, within reach).
fn match_len(input: &[u8], candidate: usize, i: usize) -> Option<usize> {
    let from = candidate.checked_sub(1)?;
    if from >= i || i - from > MAX_DISTANCE {
        return None;
    }
    let limit = MAX_MATCH.min(input.len() - i);
    let len = input[i..i + limit]
        .iter()
        .zip(&input[from..])
        .take_while(|(a, b)| a == b)
        .count();
    (len >= 3).then_some(len)
}

fn flush_literals(out: &mut Vec<u8>, literals: &[u8]) {
    for chunk in literals.chunks(MAX_LITERAL) {
        out.push((chunk.len() - 1) as u8);
        out.extend_from_slice(chunk);
    }
}

fn hash3(input: &[u8], i: usize) -> usize {
    let v = u32::from(input[i]) << 16 | u32::from(input[i + 1]) << 8 | u32::from(input[i + 2]);
    (v.wrapping_mul(2_654_435_761) >> (32 - HASH_BITS)) as usize
}

fn set(table: &mut [usize], h: usize, value: usize) {
    if let Some(slot) = table.get_mut(h) {
        *slot = value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn decodes_hand_made_stream() {
        // Literal "abc", then a reference of 6 bytes at distance 3 (overlapping: "abcabc").
        let stream = [2, b'a', b'b', b'c', (4 << 5), 2];
        assert_eq!(decompress(&stream, 9).unwrap(), b"abcabcabc");
        // Long reference: len field 7 + extra 3 = 10 → 12 bytes of a run at distance 1.
        let stream = [0, b'x', (7 << 5), 3, 0];
        assert_eq!(decompress(&stream, 13).unwrap(), vec![b'x'; 13]);
    }

    #[test]
    fn rejects_bad_streams() {
        let err = decompress(&[5, b'a'], 6).unwrap_err();
        assert_eq!(err.offset, 0);
        assert!(err.reason.contains("cut off"), "{err}");
        let err = decompress(&[0, b'a', (1 << 5), 5], 4).unwrap_err();
        assert_eq!(err.offset, 2);
        assert!(err.reason.contains("before the start"), "{err}");
        assert!(decompress(&[0, b'a'], 2).is_err());
        assert!(decompress(&[1, b'a', b'b'], 1).is_err());
        assert_eq!(decompress(&[], 0).unwrap(), Vec::<u8>::new());
    }

    #[test]
    fn compresses_runs_well() {
        let data = vec![7u8; 100_000];
        let packed = compress(&data);
        assert!(packed.len() < 1_300, "{} bytes", packed.len());
        assert_eq!(decompress(&packed, data.len()).unwrap(), data);
    }

    fn compressible() -> impl Strategy<Value = Vec<u8>> {
        // Bytes from a small alphabet with repeated chunks, so back references of all
        // lengths and distances occur.
        prop::collection::vec((0u8..4, 1usize..300), 0..40).prop_map(|runs| {
            let mut data = Vec::new();
            for (k, (symbol, len)) in runs.into_iter().enumerate() {
                if k % 3 == 2 && data.len() > 10 {
                    let from = data.len() / 3;
                    let copy: Vec<u8> = data[from..].iter().take(len).copied().collect();
                    data.extend(copy);
                } else {
                    data.extend((0..len).map(|j| symbol.wrapping_add((j % 5) as u8)));
                }
            }
            data
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        #[test]
        fn round_trip_random(data in prop::collection::vec(any::<u8>(), 0..3000)) {
            let packed = compress(&data);
            prop_assert!(packed.len() <= max_compressed_len(data.len()));
            prop_assert_eq!(decompress(&packed, data.len()).unwrap(), data);
        }

        #[test]
        fn round_trip_compressible(data in compressible()) {
            let packed = compress(&data);
            prop_assert!(packed.len() <= max_compressed_len(data.len()));
            prop_assert_eq!(decompress(&packed, data.len()).unwrap(), data);
        }

        #[test]
        fn garbage_never_panics(data in prop::collection::vec(any::<u8>(), 0..200),
                                len in 0usize..2000) {
            let _ = decompress(&data, len);
        }
    }
}
