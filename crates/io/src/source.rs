//! Opening files (with transparent gzip/bzip2 decompression) and reading them line by line or
//! byte by byte while keeping track of the place, so every error can name it.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use crate::error::{Error, Location, Result};

/// How a file is compressed.
///
/// gzip and bzip2 are recognized by their first bytes (so a `.log` that is really gzip still
/// reads), with magic numbers long enough that raw sensor data cannot imitate them. Two
/// exceptions protect binary scans, whose first bytes are arbitrary floats or integers (see
/// [`Compression::detect`]): files named `*.bin` are never decompressed, and Unix `compress`,
/// whose magic is only two bytes, is recognized only in files named `*.Z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Plain bytes.
    None,
    /// gzip (`1f 8b 08`), as in `.log.gz`.
    Gzip,
    /// bzip2 (`BZh1`–`BZh9` and a block or end-of-stream marker), as in `.clf.bz2`.
    Bzip2,
    /// Unix `compress` (`1f 9d`, LZW), as in SegComp's `.Z` files.
    Compress,
}

/// The bzip2 block-header and end-of-stream markers (BCD π and √π).
const BZIP2_BLOCK: [u8; 6] = [0x31, 0x41, 0x59, 0x26, 0x53, 0x59];
const BZIP2_END: [u8; 6] = [0x17, 0x72, 0x45, 0x38, 0x50, 0x90];

impl Compression {
    /// Recognizes the compression from the first bytes alone: gzip needs `1f 8b 08` with the
    /// reserved flag bits clear, bzip2 `BZh1`–`BZh9` and a block or end-of-stream marker, Unix
    /// compress `1f 9d` and a valid flags byte.
    pub fn sniff(head: &[u8]) -> Self {
        if head.len() >= 4 && head.starts_with(&[0x1f, 0x8b, 0x08]) && head[3] & 0xe0 == 0 {
            Compression::Gzip
        } else if head.len() >= 10
            && head.starts_with(b"BZh")
            && (b'1'..=b'9').contains(&head[3])
            && (head[4..10] == BZIP2_BLOCK || head[4..10] == BZIP2_END)
        {
            Compression::Bzip2
        } else if head.len() >= 3
            && crate::lzw::is_compressed(head)
            && (9..=16).contains(&(head[2] & 0x1f))
            && head[2] & 0x60 == 0
        {
            Compression::Compress
        } else {
            Compression::None
        }
    }

    /// The compression of the file `path` that starts with `head`: as [`Compression::sniff`],
    /// except that `*.bin` files (raw binary scans) are never compressed and Unix compress needs
    /// the `.Z` suffix.
    pub fn detect(path: &Path, head: &[u8]) -> Self {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if name.ends_with(".bin") {
            return Compression::None;
        }
        match Self::sniff(head) {
            Compression::Compress if !name.ends_with(".z") => Compression::None,
            other => other,
        }
    }
}

/// The file's length in bytes when it is stored uncompressed (so the length bounds what its
/// records can claim), `None` when it is compressed.
pub fn plain_len(path: &Path) -> Result<Option<u64>> {
    let mut file = File::open(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut head = [0u8; 16];
    let mut n = 0;
    while n < head.len() {
        match file.read(&mut head[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(Error::io(path, Location::Byte(n as u64), e)),
        }
    }
    if Compression::detect(path, &head[..n]) != Compression::None {
        return Ok(None);
    }
    let meta = file
        .metadata()
        .map_err(|e| Error::io(path, Location::File, e))?;
    Ok(Some(meta.len()))
}

/// The first bytes of a file (at most `n`) after decompression, for format detection.
pub fn peek(path: &Path, n: usize) -> Result<Vec<u8>> {
    let mut reader = open(path)?;
    let mut head = Vec::with_capacity(n);
    (&mut reader)
        .take(n as u64)
        .read_to_end(&mut head)
        .map_err(|e| Error::io(path, Location::Byte(0), e))?;
    Ok(head)
}

/// Largest decompressed size of a Unix `compress` file (it is decoded into memory).
const MAX_COMPRESS_DECOMPRESSED: usize = 1 << 30;

/// Opens a file for buffered reading, decompressing gzip and bzip2 on the fly. Unix
/// `compress` (`.Z`) files are decoded into memory first (at most 1 GiB): the format has no
/// streaming decoder here, and its users (SegComp images) are small.
pub fn open(path: &Path) -> Result<Box<dyn BufRead + Send>> {
    let file = File::open(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let head = reader
        .fill_buf()
        .map_err(|e| Error::io(path, Location::Byte(0), e))?;
    Ok(match Compression::detect(path, head) {
        Compression::None => Box::new(reader),
        Compression::Gzip => Box::new(BufReader::with_capacity(
            1 << 16,
            flate2::bufread::MultiGzDecoder::new(reader),
        )),
        Compression::Bzip2 => Box::new(BufReader::with_capacity(
            1 << 16,
            bzip2::bufread::MultiBzDecoder::new(reader),
        )),
        Compression::Compress => {
            let mut compressed = Vec::new();
            reader
                .read_to_end(&mut compressed)
                .map_err(|e| Error::io(path, Location::Byte(compressed.len() as u64), e))?;
            let bytes =
                crate::lzw::decompress(&compressed, MAX_COMPRESS_DECOMPRESSED).map_err(|e| {
                    Error::malformed(
                        path,
                        Location::Byte(e.offset),
                        format!(
                            "Unix compress (.Z) data: {} (or run `uncompress` on the file)",
                            e.reason
                        ),
                    )
                })?;
            Box::new(std::io::Cursor::new(bytes))
        }
    })
}

/// Reads a whole file into memory, decompressed.
pub fn read_all(path: &Path) -> Result<Vec<u8>> {
    let mut reader = open(path)?;
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, Location::Byte(bytes.len() as u64), e))?;
    Ok(bytes)
}

/// Reads text line by line, counting lines, for parsers whose errors name the line.
///
/// Lines end at `\n`; a trailing `\r` is removed. Invalid UTF-8 is an error naming the line.
pub struct LineReader {
    path: PathBuf,
    reader: Box<dyn BufRead + Send>,
    bytes: Vec<u8>,
    text: String,
    line: u64,
    terminated: bool,
}

impl LineReader {
    /// Opens `path` (decompressing if needed).
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self::from_boxed(open(path)?, path))
    }

    /// Reads from `reader`; `name` is used in error messages only.
    pub fn new(reader: impl BufRead + Send + 'static, name: impl Into<PathBuf>) -> Self {
        Self::from_boxed(Box::new(reader), name)
    }

    /// Like [`LineReader::new`] for a reader that is boxed already (no second box).
    fn from_boxed(reader: Box<dyn BufRead + Send>, name: impl Into<PathBuf>) -> Self {
        Self {
            path: name.into(),
            reader,
            bytes: Vec::with_capacity(4096),
            text: String::with_capacity(4096),
            line: 0,
            terminated: true,
        }
    }

    /// The next line without its line ending, or `None` at the end of the input.
    pub fn next_line(&mut self) -> Result<Option<&str>> {
        self.bytes.clear();
        let n = self
            .reader
            .read_until(b'\n', &mut self.bytes)
            .map_err(|e| Error::io(&self.path, Location::Line(self.line + 1), e))?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        self.terminated = self.bytes.last() == Some(&b'\n');
        if self.terminated {
            self.bytes.pop();
        }
        if self.bytes.last() == Some(&b'\r') {
            self.bytes.pop();
        }
        self.text.clear();
        match std::str::from_utf8(&self.bytes) {
            Ok(s) => self.text.push_str(s),
            Err(e) => {
                return Err(Error::malformed(
                    &self.path,
                    Location::Line(self.line),
                    format!("invalid UTF-8 at column {}", e.valid_up_to() + 1),
                ));
            }
        }
        Ok(Some(&self.text))
    }

    /// Whether the line last returned ended with a line break. Only the last line of the
    /// input can lack one: a file cut off mid-line, or one without a final newline.
    pub fn line_terminated(&self) -> bool {
        self.terminated
    }

    /// The 1-based number of the line last returned (0 before the first).
    pub fn line_number(&self) -> u64 {
        self.line
    }

    /// The file name used in errors.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A [`Error::Malformed`] error at the line last returned.
    pub fn error(&self, reason: impl Into<String>) -> Error {
        Error::malformed(&self.path, Location::Line(self.line), reason)
    }

    /// Gives back the underlying reader, positioned after the last line read (for formats
    /// with a text header followed by binary data).
    pub fn into_inner(self) -> Box<dyn BufRead + Send> {
        self.reader
    }
}

/// Parses one whitespace-separated field as `T`, with an error naming the field.
pub fn parse_field<T: std::str::FromStr>(
    lines: &LineReader,
    field: Option<&str>,
    what: &str,
) -> Result<T> {
    let Some(text) = field else {
        return Err(lines.error(format!("missing {what}")));
    };
    text.parse::<T>()
        .map_err(|_| lines.error(format!("{what}: cannot parse {text:?}")))
}

/// Parses the whitespace-separated fields of `line` as exactly `N` finite numbers named
/// `names` (errors name the field; `layout` describes the line for the too-many error).
pub fn finite_fields<const N: usize>(
    lines: &LineReader,
    line: &str,
    names: [&str; N],
    layout: &str,
) -> Result<[f64; N]> {
    let mut fields = line.split_whitespace();
    let mut v = [0.0f64; N];
    for (value, name) in v.iter_mut().zip(names) {
        *value = parse_field(lines, fields.next(), name)?;
        if !value.is_finite() {
            return Err(lines.error(format!("{name} is {value}")));
        }
    }
    if fields.next().is_some() {
        return Err(lines.error(format!("more than {N} numbers (expected `{layout}`)")));
    }
    Ok(v)
}

/// Reads little- and big-endian binary values while counting the byte offset.
pub struct ByteReader<R> {
    path: PathBuf,
    reader: R,
    offset: u64,
}

macro_rules! read_number {
    ($name:ident, $ty:ty, $from:ident) => {
        #[doc = concat!("Reads a `", stringify!($ty), "` (", stringify!($from), "); `what` names it in errors.")]
        pub fn $name(&mut self, what: &str) -> Result<$ty> {
            let mut bytes = [0u8; std::mem::size_of::<$ty>()];
            self.read_exact(&mut bytes, what)?;
            Ok(<$ty>::$from(bytes))
        }
    };
}

impl<R: Read> ByteReader<R> {
    /// Reads from `reader`, whose first byte is at `offset` of the source called `name`
    /// (used in error messages only).
    pub fn new(reader: R, name: impl Into<PathBuf>, offset: u64) -> Self {
        Self {
            path: name.into(),
            reader,
            offset,
        }
    }

    /// Byte offset of the next byte.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// The file name used in errors.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Fills `buf` or fails with [`Error::Truncated`] naming `what` and the offset where the
    /// read started.
    pub fn read_exact(&mut self, buf: &mut [u8], what: &str) -> Result<()> {
        let start = self.offset;
        let mut filled = 0;
        while filled < buf.len() {
            match self.reader.read(&mut buf[filled..]) {
                Ok(0) => return Err(Error::truncated(&self.path, Location::Byte(start), what)),
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => {
                    return Err(Error::io(
                        &self.path,
                        Location::Byte(start + filled as u64),
                        e,
                    ));
                }
            }
        }
        self.offset += buf.len() as u64;
        Ok(())
    }

    /// Reads `n` bytes into a new vector. `n` is checked against `limit` first, so a corrupt
    /// length field cannot make the reader allocate gigabytes.
    pub fn read_vec(&mut self, n: usize, limit: usize, what: &str) -> Result<Vec<u8>> {
        if n > limit {
            return Err(self.error(format!(
                "{what}: length {n} exceeds the limit of {limit} bytes"
            )));
        }
        let mut bytes = vec![0u8; n];
        self.read_exact(&mut bytes, what)?;
        Ok(bytes)
    }

    /// True when no byte is left. Reads at most one byte ahead, which is kept.
    pub fn at_end(&mut self) -> Result<bool>
    where
        R: BufRead,
    {
        let buf = self
            .reader
            .fill_buf()
            .map_err(|e| Error::io(&self.path, Location::Byte(self.offset), e))?;
        Ok(buf.is_empty())
    }

    /// A [`Error::Malformed`] error at the current offset.
    pub fn error(&self, reason: impl Into<String>) -> Error {
        Error::malformed(&self.path, Location::Byte(self.offset), reason)
    }

    /// A [`Error::Malformed`] error at `offset`.
    pub fn error_at(&self, offset: u64, reason: impl Into<String>) -> Error {
        Error::malformed(&self.path, Location::Byte(offset), reason)
    }

    read_number!(read_u8, u8, from_le_bytes);
    read_number!(read_u16_le, u16, from_le_bytes);
    read_number!(read_u32_le, u32, from_le_bytes);
    read_number!(read_i32_le, i32, from_le_bytes);
    read_number!(read_u64_le, u64, from_le_bytes);
    read_number!(read_f32_le, f32, from_le_bytes);
    read_number!(read_f64_le, f64, from_le_bytes);
    read_number!(read_u16_be, u16, from_be_bytes);
    read_number!(read_i32_be, i32, from_be_bytes);
    read_number!(read_u32_be, u32, from_be_bytes);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Cursor, Write};

    #[test]
    fn sniff_compression() {
        assert_eq!(Compression::sniff(&[0x1f, 0x8b, 8, 0]), Compression::Gzip);
        assert_eq!(Compression::sniff(&[0x1f, 0x8b, 7, 0]), Compression::None);
        let mut bz = b"BZh9".to_vec();
        bz.extend_from_slice(&BZIP2_BLOCK);
        assert_eq!(Compression::sniff(&bz), Compression::Bzip2);
        assert_eq!(Compression::sniff(b"BZh9abcdef"), Compression::None);
        assert_eq!(Compression::sniff(b"BZhx"), Compression::None);
        assert_eq!(Compression::sniff(b"FLASER"), Compression::None);
        assert_eq!(
            Compression::sniff(&[0x1f, 0x9d, 0x90]),
            Compression::Compress
        );
        assert_eq!(Compression::sniff(&[0x1f, 0x9d, 0x02]), Compression::None);
    }

    #[test]
    fn binary_scans_are_never_taken_for_compressed_files() {
        // A KITTI scan whose first float happens to start with the bytes of a magic number.
        let head = [0x1f, 0x9d, 0x90, 0x41, 0, 0, 0, 0];
        assert_eq!(
            Compression::detect(Path::new("000075.bin"), &head),
            Compression::None
        );
        assert_eq!(
            Compression::detect(Path::new("scan.dat"), &head),
            Compression::None
        );
        assert_eq!(
            Compression::detect(Path::new("perc.test.1.Z"), &head),
            Compression::Compress
        );
        let gz = [0x1f, 0x8b, 8, 0];
        assert_eq!(
            Compression::detect(Path::new("000001.bin"), &gz),
            Compression::None
        );
        assert_eq!(
            Compression::detect(Path::new("intel.log"), &gz),
            Compression::Gzip
        );
    }

    #[test]
    fn reads_gzip_lines_with_numbers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.log.gz");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(b"one\r\ntwo\nthree").unwrap();
        std::fs::write(&path, enc.finish().unwrap()).unwrap();
        let mut lines = LineReader::open(&path).unwrap();
        assert_eq!(lines.next_line().unwrap(), Some("one"));
        assert_eq!(lines.next_line().unwrap(), Some("two"));
        assert_eq!(lines.next_line().unwrap(), Some("three"));
        assert_eq!(lines.line_number(), 3);
        assert_eq!(lines.next_line().unwrap(), None);
    }

    #[test]
    fn opens_unix_compress_files() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/lzw/tobe.Z"
        ));
        let mut lines = LineReader::open(path).unwrap();
        assert_eq!(
            lines.next_line().unwrap(),
            Some("TOBEORNOTTOBEORTOBEORNOT#")
        );
    }

    #[test]
    fn invalid_utf8_names_line() {
        let mut lines = LineReader::new(Cursor::new(b"ok\nb\xffad\n".to_vec()), "x.txt");
        lines.next_line().unwrap();
        let err = lines.next_line().unwrap_err().to_string();
        assert!(err.starts_with("x.txt:2: invalid UTF-8"), "{err}");
    }

    #[test]
    fn truncated_binary_names_offset() {
        let mut bytes = ByteReader::new(Cursor::new(vec![1u8, 0, 0, 0, 7]), "b.bin", 0);
        assert_eq!(bytes.read_u32_le("count").unwrap(), 1);
        let err = bytes.read_u32_le("point x").unwrap_err().to_string();
        assert_eq!(
            err,
            "b.bin: byte 4: unexpected end of file while reading point x"
        );
    }
}
