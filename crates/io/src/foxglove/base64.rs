//! Standard base64 (RFC 4648 §4, alphabet `A–Z a–z 0–9 + /`, `=` padding): how JSON messages
//! carry the byte fields `Grid.data` and `PointCloud.data`.

const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Appends the base64 encoding of `bytes` to `out`: every 3 bytes become 4 characters, a
/// final group of 1 or 2 bytes is padded with `==` or `=`.
pub fn encode_into(bytes: &[u8], out: &mut String) {
    out.reserve(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for chunk in &mut chunks {
        let n = u32::from(chunk[0]) << 16 | u32::from(chunk[1]) << 8 | u32::from(chunk[2]);
        for shift in [18, 12, 6, 0] {
            out.push(char::from(ALPHABET[(n >> shift & 63) as usize]));
        }
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let b1 = rest.get(1).copied().unwrap_or(0);
        let n = u32::from(rest[0]) << 16 | u32::from(b1) << 8;
        out.push(char::from(ALPHABET[(n >> 18 & 63) as usize]));
        out.push(char::from(ALPHABET[(n >> 12 & 63) as usize]));
        if rest.len() == 2 {
            out.push(char::from(ALPHABET[(n >> 6 & 63) as usize]));
        } else {
            out.push('=');
        }
        out.push('=');
    }
}

/// The base64 encoding of `bytes`.
pub fn encode(bytes: &[u8]) -> String {
    let mut out = String::new();
    encode_into(bytes, &mut out);
    out
}

/// Decodes padded standard base64 (the inverse of [`encode`]); `None` on any other input.
/// Used by the tests to read back what the writer produced.
#[cfg(test)]
pub fn decode(text: &str) -> Option<Vec<u8>> {
    let bytes = text.as_bytes();
    if bytes.len() % 4 != 0 {
        return None;
    }
    let value = |c: u8| ALPHABET.iter().position(|&a| a == c).map(|v| v as u32);
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3);
    for (i, group) in bytes.chunks_exact(4).enumerate() {
        let last = i + 1 == bytes.len() / 4;
        let pad = group.iter().rev().take_while(|&&c| c == b'=').count();
        if pad > 2 || (pad > 0 && !last) {
            return None;
        }
        let mut n = 0u32;
        for &c in &group[..4 - pad] {
            n = n << 6 | value(c)?;
        }
        n <<= 6 * pad as u32;
        let decoded = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        out.extend_from_slice(&decoded[..3 - pad]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rfc4648_test_vectors() {
        // RFC 4648 §10.
        let cases = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, coded) in cases {
            assert_eq!(encode(plain.as_bytes()), coded, "encode({plain:?})");
            assert_eq!(
                decode(coded).unwrap(),
                plain.as_bytes(),
                "decode({coded:?})"
            );
        }
    }

    #[test]
    fn every_byte_value_round_trips_at_every_length() {
        let bytes: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
        for len in 0..bytes.len() {
            let coded = encode(&bytes[..len]);
            assert_eq!(coded.len(), len.div_ceil(3) * 4);
            assert_eq!(decode(&coded).unwrap(), &bytes[..len]);
        }
        // The high alphabet: 0xFB 0xFF 0xBF encodes to "+/+/".
        assert_eq!(encode(&[0xFB, 0xFF, 0xBF]), "+/+/");
    }

    #[test]
    fn decode_rejects_malformed_text() {
        for bad in ["Zg=", "Z===", "Zg==Zg==", "Zm9*", "Zm9"] {
            assert_eq!(decode(bad), None, "{bad:?}");
        }
    }
}
