//! Decoder for Unix `compress` files (`.Z`, LZW), the packaging of the SegComp images.
//!
//! Format (as written by `compress`/ncompress 4.x and read by `gzip -d`):
//!
//! * three header bytes `1f 9d f`, where `f & 0x1f` is the largest code width `maxbits`
//!   (9–16) and `f & 0x80` selects **block mode** (code 256 clears the dictionary);
//! * then LZW codes packed least-significant bit first, starting 9 bits wide. Codes 0–255 are
//!   bytes; each further code adds the dictionary entry "previous string + first byte of the
//!   current string" (the `KwKwK` case: a code equal to the next free entry);
//! * the width grows by one bit when the next free entry exceeds the largest code of the
//!   current width, up to `maxbits`. Codes are written in groups of eight (a group of `n`-bit
//!   codes is `n` bytes); when the width changes, or after a clear code, the rest of the
//!   current group is padding and is skipped — the quirk that makes naïve LZW decoders fail
//!   on real `.Z` files.
//!
//! Tested against files produced by ncompress 4.2.4.6 (`tests/data/lzw/*.Z`, with 9-, 12-
//! and 16-bit codes and clear codes) and, when a `compress` program is installed, against
//! random data compressed on the spot.

/// The magic bytes of a `.Z` file.
pub const MAGIC: [u8; 2] = [0x1f, 0x9d];
const BLOCK_MODE: u8 = 0x80;
const CLEAR: usize = 256;

/// True when `bytes` start like a Unix `compress` file.
pub fn is_compressed(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// Why a `.Z` stream could not be decoded: a byte offset in the compressed input and a reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LzwError {
    /// Byte offset in the compressed input.
    pub offset: u64,
    /// What is wrong.
    pub reason: String,
}

/// Decompresses a whole `.Z` stream. Output beyond `limit` bytes is an error (a corrupt or
/// hostile file could otherwise expand without bound).
pub fn decompress(input: &[u8], limit: usize) -> Result<Vec<u8>, LzwError> {
    let fail = |offset: u64, reason: String| LzwError { offset, reason };
    if !is_compressed(input) {
        return Err(fail(
            0,
            "not a Unix compress (.Z) stream: magic 1f 9d missing".into(),
        ));
    }
    let Some(&flags) = input.get(2) else {
        return Err(fail(2, "the flags byte is missing".into()));
    };
    let max_bits = u32::from(flags & 0x1f);
    if !(9..=16).contains(&max_bits) {
        return Err(fail(
            2,
            format!("code width {max_bits} is not between 9 and 16"),
        ));
    }
    if flags & 0x60 != 0 {
        return Err(fail(2, format!("unknown flags {flags:#04x}")));
    }
    let block_mode = flags & BLOCK_MODE != 0;
    let data = input.get(3..).unwrap_or_default();
    let total_bits = data.len() as u64 * 8;
    let max_max_code = 1usize << max_bits;

    let mut prefix = vec![0u16; max_max_code];
    let mut suffix = vec![0u8; max_max_code];
    for (i, s) in suffix.iter_mut().enumerate().take(256) {
        *s = i as u8;
    }
    let mut out = Vec::with_capacity(input.len().saturating_mul(3).min(limit));
    let mut stack: Vec<u8> = Vec::with_capacity(1 << 12);

    let mut n_bits = 9u32;
    let mut max_code = (1usize << n_bits) - 1;
    let mut free_entry = if block_mode { 257 } else { 256 };
    let mut position = 0u64; // bit position in `data`
    let mut group_start = 0u64; // where codes of the current width began
    let mut old_code: Option<usize> = None;
    let mut last_byte = 0u8;

    loop {
        if free_entry > max_code && n_bits < max_bits {
            position = align(position, group_start, n_bits);
            group_start = position;
            n_bits += 1;
            max_code = if n_bits == max_bits {
                max_max_code
            } else {
                (1 << n_bits) - 1
            };
        }
        if position + u64::from(n_bits) > total_bits {
            break;
        }
        let code_offset = 3 + position / 8;
        let code = read_code(data, position, n_bits);
        position += u64::from(n_bits);

        let Some(previous) = old_code else {
            if code >= 256 {
                return Err(fail(
                    code_offset,
                    format!("first code {code} is not a byte"),
                ));
            }
            last_byte = code as u8;
            push(&mut out, &[last_byte], limit).map_err(|r| fail(code_offset, r))?;
            old_code = Some(code);
            continue;
        };
        if code == CLEAR && block_mode {
            prefix.fill(0);
            free_entry = CLEAR;
            position = align(position, group_start, n_bits);
            group_start = position;
            n_bits = 9;
            max_code = (1 << n_bits) - 1;
            continue;
        }
        stack.clear();
        let mut current = code;
        if code >= free_entry {
            if code > free_entry {
                return Err(fail(
                    code_offset,
                    format!("code {code} is beyond the next dictionary entry {free_entry}"),
                ));
            }
            stack.push(last_byte);
            current = previous;
        }
        while current >= 256 {
            if stack.len() > max_max_code {
                return Err(fail(
                    code_offset,
                    "dictionary entry refers to itself".into(),
                ));
            }
            stack.push(suffix.get(current).copied().unwrap_or_default());
            current = usize::from(prefix.get(current).copied().unwrap_or_default());
        }
        last_byte = current as u8;
        stack.push(last_byte);
        stack.reverse();
        push(&mut out, &stack, limit).map_err(|r| fail(code_offset, r))?;
        if free_entry < max_max_code {
            if let Some(p) = prefix.get_mut(free_entry) {
                *p = previous as u16;
            }
            if let Some(s) = suffix.get_mut(free_entry) {
                *s = last_byte;
            }
            free_entry += 1;
        }
        old_code = Some(code);
    }
    Ok(out)
}

/// Rounds `position` up to the end of the current group of eight `n_bits` codes.
fn align(position: u64, group_start: u64, n_bits: u32) -> u64 {
    let group = u64::from(n_bits) * 8;
    let used = position - group_start;
    group_start + used.div_ceil(group) * group
}

/// The `n_bits` code at bit `position`, least-significant bit first.
fn read_code(data: &[u8], position: u64, n_bits: u32) -> usize {
    let byte = (position / 8) as usize;
    let mut window = 0u32;
    for k in 0..3 {
        window |= u32::from(data.get(byte + k).copied().unwrap_or(0)) << (8 * k);
    }
    ((window >> (position % 8)) & ((1 << n_bits) - 1)) as usize
}

fn push(out: &mut Vec<u8>, bytes: &[u8], limit: usize) -> Result<(), String> {
    if out.len() + bytes.len() > limit {
        return Err(format!(
            "decompressed data exceeds the limit of {limit} bytes"
        ));
    }
    out.extend_from_slice(bytes);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn rejects_bad_headers() {
        assert!(decompress(b"abc", 100).is_err());
        assert_eq!(decompress(&[0x1f, 0x9d], 100).unwrap_err().offset, 2);
        assert!(
            decompress(&[0x1f, 0x9d, 0x88], 100)
                .unwrap_err()
                .reason
                .contains("width 8")
        );
        assert!(decompress(&[0x1f, 0x9d, 0x90], 100).unwrap().is_empty());
    }

    #[test]
    fn decodes_hand_packed_codes() {
        // Codes 'a' (97), 'b' (98), 257 and 259 (the KwKwK case), packed 9 bits LSB first,
        // block mode, 16-bit maximum.
        let codes = [97usize, 98, 257, 259];
        let mut bits = 0u64;
        let mut acc = 0u128;
        for c in codes {
            acc |= (c as u128) << bits;
            bits += 9;
        }
        let mut stream = vec![0x1f, 0x9d, 0x90];
        stream.extend(acc.to_le_bytes().iter().take(bits.div_ceil(8) as usize));
        // 97 → "a"; 98 → "b" (entry 257 = "ab"); 257 → "ab" (258 = "ba");
        // 259 = next free → "ab" + 'a' = "aba": "a" "b" "ab" "aba".
        assert_eq!(decompress(&stream, 100).unwrap(), b"abababa");
    }

    #[test]
    fn limit_is_enforced() {
        let stream = [0x1f, 0x9d, 0x90, 97, 0];
        assert!(decompress(&stream, 0).unwrap_err().reason.contains("limit"));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1500))]

        #[test]
        fn garbage_never_panics(flags in any::<u8>(), body in prop::collection::vec(any::<u8>(), 0..300)) {
            let mut stream = vec![0x1f, 0x9d, flags];
            stream.extend(body);
            let _ = decompress(&stream, 1 << 16);
        }
    }
}
