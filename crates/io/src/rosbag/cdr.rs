//! Classic CDR (XCDR1), the serialization of ROS 2 messages in rosbag2 recordings.
//!
//! A message starts with a 4-byte encapsulation header: `00 01` little-endian CDR,
//! `00 00` big-endian CDR, then two option bytes. Primitives are aligned to their size (at
//! most 8) relative to the first byte after the header; strings are a `u32` length that
//! counts the terminating NUL, then the bytes and the NUL; sequences are a `u32` element
//! count, then the elements; fixed-size arrays have no count.

use std::fmt;

/// Size of the encapsulation header.
pub const HEADER_LEN: usize = 4;

/// A CDR decoding error: the byte offset in the message (header included) and the reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CdrError {
    /// Offset in the serialized message, counting the encapsulation header.
    pub offset: usize,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CDR byte {}: {}", self.offset, self.reason)
    }
}

impl std::error::Error for CdrError {}

/// `Result` of CDR decoding.
pub type CdrResult<T> = Result<T, CdrError>;

/// Reads CDR primitives from a serialized message.
#[derive(Clone, Debug)]
pub struct CdrReader<'a> {
    /// The bytes after the encapsulation header.
    body: &'a [u8],
    pos: usize,
    big_endian: bool,
}

macro_rules! read_primitive {
    ($name:ident, $t:ty, $n:expr) => {
        #[doc = concat!("Reads an aligned `", stringify!($t), "`.")]
        pub fn $name(&mut self) -> CdrResult<$t> {
            let bytes: [u8; $n] = self.take_aligned::<$n>(stringify!($t))?;
            Ok(if self.big_endian {
                <$t>::from_be_bytes(bytes)
            } else {
                <$t>::from_le_bytes(bytes)
            })
        }
    };
}

impl<'a> CdrReader<'a> {
    /// Checks the encapsulation header of `message` (plain CDR, either byte order).
    pub fn new(message: &'a [u8]) -> CdrResult<Self> {
        let Some((header, body)) = message.split_first_chunk::<HEADER_LEN>() else {
            return Err(CdrError {
                offset: 0,
                reason: format!(
                    "{} bytes: too short for the 4-byte encapsulation header",
                    message.len()
                ),
            });
        };
        let big_endian = match [header[0], header[1]] {
            [0, 0] => true,
            [0, 1] => false,
            kind => {
                return Err(CdrError {
                    offset: 0,
                    reason: format!(
                        "encapsulation {:02x} {:02x} is not plain CDR (00 00 big endian or \
                         00 01 little endian; XCDR2 and parameter lists are not supported)",
                        kind[0], kind[1]
                    ),
                });
            }
        };
        Ok(Self {
            body,
            pos: 0,
            big_endian,
        })
    }

    /// True for big-endian data.
    pub fn is_big_endian(&self) -> bool {
        self.big_endian
    }

    /// Offset of the next byte in the message (header included).
    pub fn offset(&self) -> usize {
        self.pos + HEADER_LEN
    }

    /// Bytes left after the current position.
    pub fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// An error at the current position.
    pub fn error(&self, reason: impl Into<String>) -> CdrError {
        CdrError {
            offset: self.offset(),
            reason: reason.into(),
        }
    }

    fn end_error(&self, need: usize, what: &str) -> CdrError {
        self.error(format!(
            "message ends while reading {what}: {need} bytes needed, {} left",
            self.remaining()
        ))
    }

    /// Skips padding up to a multiple of `n` (relative to the end of the header).
    pub fn align(&mut self, n: usize) -> CdrResult<()> {
        let padded = self.pos.next_multiple_of(n);
        if padded > self.body.len() {
            return Err(self.end_error(padded - self.pos, "alignment padding"));
        }
        self.pos = padded;
        Ok(())
    }

    fn take_aligned<const N: usize>(&mut self, what: &str) -> CdrResult<[u8; N]> {
        self.align(N)?;
        match self.body[self.pos..].first_chunk::<N>() {
            Some(bytes) => {
                self.pos += N;
                Ok(*bytes)
            }
            None => Err(self.end_error(N, what)),
        }
    }

    /// Reads `n` unaligned bytes.
    pub fn bytes(&mut self, n: usize, what: &str) -> CdrResult<&'a [u8]> {
        if n > self.remaining() {
            return Err(self.end_error(n, what));
        }
        let out = &self.body[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    read_primitive!(u8, u8, 1);
    read_primitive!(u16, u16, 2);
    read_primitive!(i16, i16, 2);
    read_primitive!(u32, u32, 4);
    read_primitive!(i32, i32, 4);
    read_primitive!(u64, u64, 8);
    read_primitive!(f32, f32, 4);
    read_primitive!(f64, f64, 8);

    /// Reads a `bool` (one byte, 0 or 1).
    pub fn bool(&mut self) -> CdrResult<bool> {
        let at = self.offset();
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(CdrError {
                offset: at,
                reason: format!("bool byte is {v}, not 0 or 1"),
            }),
        }
    }

    /// Reads a string: `u32` length including the NUL, the bytes, the NUL.
    pub fn string(&mut self) -> CdrResult<&'a str> {
        let at = self.offset();
        let len = self.u32()? as usize;
        if len == 0 {
            // Not what the standard says, but some writers serialize "" this way.
            return Ok("");
        }
        let bytes = self.bytes(len, "a string")?;
        let Some((&0, text)) = bytes.split_last() else {
            return Err(CdrError {
                offset: at,
                reason: format!("string of length {len} does not end with NUL"),
            });
        };
        std::str::from_utf8(text).map_err(|e| CdrError {
            offset: at + 4,
            reason: format!("string is not UTF-8: {e}"),
        })
    }

    /// Reads a sequence length and checks that `count × min_elem_size` bytes remain.
    pub fn seq_len(&mut self, min_elem_size: usize, what: &str) -> CdrResult<usize> {
        let at = self.offset();
        let count = self.u32()? as usize;
        if count.saturating_mul(min_elem_size) > self.remaining() {
            return Err(CdrError {
                offset: at,
                reason: format!(
                    "{what}: {count} elements of at least {min_elem_size} bytes, but only {} \
                     bytes left",
                    self.remaining()
                ),
            });
        }
        Ok(count)
    }

    /// Reads a `float32[]` sequence, converting each value with `f` into `out` (cleared).
    pub fn f32_seq_into<T>(
        &mut self,
        out: &mut Vec<T>,
        what: &str,
        mut f: impl FnMut(f32) -> T,
    ) -> CdrResult<()> {
        let n = self.seq_len(4, what)?;
        self.align(4)?;
        let bytes = self.bytes(n * 4, what)?;
        out.clear();
        out.reserve(n);
        if self.big_endian {
            out.extend(
                bytes
                    .chunks_exact(4)
                    .map(|c| f(f32::from_be_bytes([c[0], c[1], c[2], c[3]]))),
            );
        } else {
            out.extend(
                bytes
                    .chunks_exact(4)
                    .map(|c| f(f32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            );
        }
        Ok(())
    }

    /// Reads a `uint8[]` sequence.
    pub fn byte_seq(&mut self, what: &str) -> CdrResult<&'a [u8]> {
        let n = self.seq_len(1, what)?;
        self.bytes(n, what)
    }

    /// Skips `n` aligned `float64` values (a fixed-size array).
    pub fn skip_f64s(&mut self, n: usize, what: &str) -> CdrResult<()> {
        if n == 0 {
            return Ok(());
        }
        self.align(8)?;
        self.bytes(n * 8, what).map(|_| ())
    }
}

/// Writes CDR primitives (little endian) after an encapsulation header.
#[derive(Clone, Debug)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

macro_rules! write_primitive {
    ($name:ident, $t:ty) => {
        #[doc = concat!("Writes an aligned `", stringify!($t), "`.")]
        pub fn $name(&mut self, v: $t) {
            self.align(std::mem::size_of::<$t>());
            self.buf.extend_from_slice(&v.to_le_bytes());
        }
    };
}

impl CdrWriter {
    /// A writer holding the little-endian encapsulation header.
    pub fn new() -> Self {
        let mut w = Self {
            buf: Vec::with_capacity(256),
        };
        w.reset();
        w
    }

    /// Clears the message (keeping the allocation) and writes the header again.
    pub fn reset(&mut self) {
        self.buf.clear();
        self.buf.extend_from_slice(&[0, 1, 0, 0]);
    }

    /// The serialized message.
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }

    /// Pads with zeros to a multiple of `n` relative to the end of the header.
    pub fn align(&mut self, n: usize) {
        let body = self.buf.len() - HEADER_LEN;
        let padded = body.next_multiple_of(n);
        self.buf.resize(HEADER_LEN + padded, 0);
    }

    write_primitive!(u8, u8);
    write_primitive!(u32, u32);
    write_primitive!(i32, i32);
    write_primitive!(f32, f32);
    write_primitive!(f64, f64);

    /// Writes a `bool`.
    pub fn bool(&mut self, v: bool) {
        self.u8(u8::from(v));
    }

    /// Writes a string with its NUL.
    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// Writes a sequence length.
    pub fn seq_len(&mut self, n: usize) {
        self.u32(n as u32);
    }

    /// Writes a `float32[]` sequence.
    pub fn f32_seq(&mut self, values: impl ExactSizeIterator<Item = f32>) {
        self.seq_len(values.len());
        self.align(4);
        for v in values {
            self.buf.extend_from_slice(&v.to_le_bytes());
        }
    }

    /// Writes a `uint8[]` sequence from its length and a closure that appends exactly `n`
    /// bytes.
    pub fn byte_seq_with(&mut self, n: usize, fill: impl FnOnce(&mut Vec<u8>)) {
        self.seq_len(n);
        let start = self.buf.len();
        fill(&mut self.buf);
        debug_assert_eq!(self.buf.len() - start, n);
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn alignment_is_relative_to_the_header() {
        let mut w = CdrWriter::new();
        w.u8(7);
        w.f64(1.5);
        w.string("ab");
        w.u32(9);
        let bytes = w.bytes().to_vec();
        // u8 at 4, f64 at 4 + 8 = 12, string length at 20, "ab\0" to 27, u32 at 28.
        assert_eq!(bytes.len(), 32);
        assert_eq!(&bytes[12..20], &1.5f64.to_le_bytes());
        assert_eq!(&bytes[20..24], &3u32.to_le_bytes());
        assert_eq!(&bytes[24..27], b"ab\0");
        let mut r = CdrReader::new(&bytes).unwrap();
        assert_eq!(r.u8().unwrap(), 7);
        assert_eq!(r.f64().unwrap(), 1.5);
        assert_eq!(r.string().unwrap(), "ab");
        assert_eq!(r.u32().unwrap(), 9);
        assert_eq!(r.remaining(), 0);
    }

    #[test]
    fn big_endian() {
        let mut bytes = vec![0, 0, 0, 0];
        bytes.extend_from_slice(&[0, 0, 0, 2, 0, 0, 0, 0]);
        bytes.extend_from_slice(&2.5f64.to_be_bytes());
        let mut r = CdrReader::new(&bytes).unwrap();
        assert!(r.is_big_endian());
        assert_eq!(r.u32().unwrap(), 2);
        assert_eq!(r.f64().unwrap(), 2.5);
    }

    #[test]
    fn float_sequences() {
        let mut w = CdrWriter::new();
        w.u8(1);
        w.f32_seq([1.0f32, -2.0, f32::INFINITY].into_iter());
        let mut r = CdrReader::new(w.bytes()).unwrap();
        r.u8().unwrap();
        let mut out = Vec::new();
        r.f32_seq_into(&mut out, "ranges", f64::from).unwrap();
        assert_eq!(out, vec![1.0, -2.0, f64::INFINITY]);
    }

    #[test]
    fn errors_name_the_offset() {
        let e = CdrReader::new(&[0, 1]).unwrap_err();
        assert_eq!(e.offset, 0);
        let e = CdrReader::new(&[0, 7, 0, 0]).unwrap_err();
        assert!(e.reason.contains("not plain CDR"), "{e}");
        let mut w = CdrWriter::new();
        w.u32(1000);
        let mut r = CdrReader::new(w.bytes()).unwrap();
        let e = r.seq_len(4, "ranges").unwrap_err();
        assert_eq!(e.offset, 4);
        assert!(
            e.to_string()
                .starts_with("CDR byte 4: ranges: 1000 elements"),
            "{e}"
        );
        let mut r = CdrReader::new(&[0, 1, 0, 0, 1, 2]).unwrap();
        r.u8().unwrap();
        let e = r.f64().unwrap_err();
        assert!(
            e.to_string().contains("padding") || e.to_string().contains("f64"),
            "{e}"
        );
        let mut bad_string = CdrWriter::new();
        bad_string.u32(2);
        let mut bytes = bad_string.bytes().to_vec();
        bytes.extend_from_slice(b"ab");
        let e = CdrReader::new(&bytes).unwrap().string().unwrap_err();
        assert!(e.reason.contains("NUL"), "{e}");
    }
}
