//! LZ4 frames (the format MCAP's `lz4` chunks use), decoded block by block straight into the
//! chunk's buffer: no intermediate copies, linked blocks read their dictionary from the
//! output itself. Checksums (XXH32) are checked when asked: a chunk with a CRC of its own
//! needs no second one.

/// Frame magic number.
const MAGIC: u32 = 0x184D_2204;
/// Skippable frames have magic numbers `0x184D2A50..=0x184D2A5F`.
const SKIPPABLE: u32 = 0x184D_2A50;

/// Where decoding is in the input, and what the current frame declared.
#[derive(Clone, Debug, Default)]
pub(super) struct Lz4Frames {
    /// Next input byte.
    at: usize,
    /// In a frame's blocks (else at a frame header).
    in_frame: bool,
    block_checksums: bool,
    content_checksum: bool,
    block_max: usize,
    /// Output offset where the current frame's content starts.
    frame_start: usize,
}

/// What one step produced.
pub(super) enum Step {
    /// Output bytes appended (maybe none: a header or skippable frame was read).
    Progress,
    /// The input ends here (with the frames complete, or cut short).
    End,
}

impl Lz4Frames {
    /// Frames starting at byte `at` of the input.
    pub(super) fn at(at: usize) -> Self {
        Self {
            at,
            ..Self::default()
        }
    }

    /// True inside a frame (its end mark not read yet).
    pub(super) fn in_frame(&self) -> bool {
        self.in_frame
    }

    /// Decodes the next block (or frame header) of `input` (up to `stop`), appending to
    /// `out`, which must not grow past `limit` bytes. `check`: verify XXH32 checksums.
    pub(super) fn step(
        &mut self,
        input: &[u8],
        out: &mut Vec<u8>,
        limit: usize,
        check: bool,
    ) -> Result<Step, String> {
        if !self.in_frame {
            return self.header(input, out.len());
        }
        let Some(word) = u32_at(input, self.at) else {
            return Ok(Step::End);
        };
        if word == 0 {
            // End mark, then the content checksum.
            let mut next = self.at + 4;
            if self.content_checksum {
                let Some(sum) = u32_at(input, next) else {
                    return Ok(Step::End);
                };
                if check && xxh32(&out[self.frame_start..]) != sum {
                    return Err("lz4: content checksum mismatch".into());
                }
                next += 4;
            }
            self.at = next;
            self.in_frame = false;
            return Ok(Step::Progress);
        }
        let size = (word & 0x7FFF_FFFF) as usize;
        if size > self.block_max {
            return Err(format!(
                "lz4: block of {size} bytes in a frame of {}-byte blocks",
                self.block_max
            ));
        }
        let start = self.at + 4;
        let end = start.saturating_add(size);
        let after = end.saturating_add(if self.block_checksums { 4 } else { 0 });
        if after > input.len() {
            return Ok(Step::End);
        }
        let block = &input[start..end];
        if self.block_checksums && check && u32_at(input, end) != Some(xxh32(block)) {
            return Err("lz4: block checksum mismatch".into());
        }
        let room = limit.saturating_sub(out.len()).min(self.block_max);
        if word & 0x8000_0000 != 0 {
            if size > room {
                return Err(
                    "lz4: the frame decompresses to more bytes than the chunk header says".into(),
                );
            }
            out.extend_from_slice(block);
        } else {
            decode_block(block, out, room)?;
        }
        self.at = after;
        Ok(Step::Progress)
    }

    /// Reads a frame header (or skips a skippable frame).
    fn header(&mut self, input: &[u8], out_len: usize) -> Result<Step, String> {
        let Some(magic) = u32_at(input, self.at) else {
            return Ok(Step::End);
        };
        if magic & 0xFFFF_FFF0 == SKIPPABLE {
            let Some(size) = u32_at(input, self.at + 4) else {
                return Ok(Step::End);
            };
            self.at = self.at.saturating_add(8).saturating_add(size as usize);
            return Ok(Step::Progress);
        }
        if magic != MAGIC {
            return Err(format!("lz4: not an LZ4 frame (magic {magic:#010x})"));
        }
        let d = self.at + 4;
        let (Some(&flg), Some(&bd)) = (input.get(d), input.get(d + 1)) else {
            return Ok(Step::End);
        };
        if flg >> 6 != 1 || flg & 0b10 != 0 || bd & 0x8F != 0 {
            return Err(format!(
                "lz4: unsupported frame descriptor {flg:#04x} {bd:#04x}"
            ));
        }
        let len = 2 + if flg & 0b1000 != 0 { 8 } else { 0 } + if flg & 1 != 0 { 4 } else { 0 };
        let Some(&hc) = input.get(d + len) else {
            return Ok(Step::End);
        };
        if (xxh32(&input[d..d + len]) >> 8) as u8 != hc {
            return Err("lz4: frame header checksum mismatch".into());
        }
        if flg & 1 != 0 {
            return Err("lz4: frames with a dictionary are not supported".into());
        }
        self.block_max = match (bd >> 4) & 7 {
            4 => 64 << 10,
            5 => 256 << 10,
            6 => 1 << 20,
            7 => 4 << 20,
            other => return Err(format!("lz4: block size code {other}")),
        };
        self.block_checksums = flg & 0b1_0000 != 0;
        self.content_checksum = flg & 0b100 != 0;
        self.frame_start = out_len;
        self.in_frame = true;
        self.at = d + len + 1;
        Ok(Step::Progress)
    }
}

fn u32_at(input: &[u8], at: usize) -> Option<u32> {
    let b = input.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// An LZ4 length: `nibble`, extended by bytes while they are 255.
fn length(block: &[u8], p: &mut usize, nibble: usize) -> Result<usize, String> {
    let mut len = nibble;
    if nibble == 15 {
        loop {
            let b = *block.get(*p).ok_or("lz4: block ends inside a length")?;
            *p += 1;
            len += usize::from(b);
            if b != 255 {
                break;
            }
        }
    }
    Ok(len)
}

/// Decodes one LZ4 block, appending at most `room` bytes to `out` (whose earlier bytes are
/// the dictionary of linked blocks).
fn decode_block(block: &[u8], out: &mut Vec<u8>, room: usize) -> Result<(), String> {
    let limit = out.len() + room;
    let mut p = 0;
    loop {
        let token = *block.get(p).ok_or("lz4: empty block")?;
        p += 1;
        let lits = length(block, &mut p, usize::from(token >> 4))?;
        let lit_end = p.checked_add(lits).filter(|&e| e <= block.len());
        let Some(lit_end) = lit_end else {
            return Err("lz4: literals run past the block".into());
        };
        if out.len() + lits > limit {
            return Err(
                "lz4: the frame decompresses to more bytes than the chunk header says".into(),
            );
        }
        out.extend_from_slice(&block[p..lit_end]);
        p = lit_end;
        if p == block.len() {
            return Ok(());
        }
        let (Some(&lo), Some(&hi)) = (block.get(p), block.get(p + 1)) else {
            return Err("lz4: block ends inside an offset".into());
        };
        p += 2;
        let offset = usize::from(u16::from_le_bytes([lo, hi]));
        if offset == 0 || offset > out.len() {
            return Err(format!(
                "lz4: match offset {offset} before the start of the output"
            ));
        }
        let len = length(block, &mut p, usize::from(token & 15))? + 4;
        if out.len() + len > limit {
            return Err(
                "lz4: the frame decompresses to more bytes than the chunk header says".into(),
            );
        }
        let from = out.len() - offset;
        if offset >= len {
            out.extend_from_within(from..from + len);
        } else {
            // Overlapping: the pattern repeats; copy it doubling each time.
            let mut left = len;
            while left > 0 {
                let n = left.min(out.len() - from);
                out.extend_from_within(from..from + n);
                left -= n;
            }
        }
    }
}

const P1: u32 = 0x9E37_79B1;
const P2: u32 = 0x85EB_CA77;
const P3: u32 = 0xC2B2_AE3D;
const P4: u32 = 0x27D4_EB2F;
const P5: u32 = 0x1656_67B1;

/// XXH32 with seed 0 (LZ4 frames' header, block and content checksums).
pub(super) fn xxh32(data: &[u8]) -> u32 {
    let lane = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let round = |acc: u32, v: u32| {
        acc.wrapping_add(v.wrapping_mul(P2))
            .rotate_left(13)
            .wrapping_mul(P1)
    };
    let mut stripes = data.chunks_exact(16);
    let mut acc = if data.len() >= 16 {
        let mut v = [P1.wrapping_add(P2), P2, 0, 0u32.wrapping_sub(P1)];
        for s in &mut stripes {
            for (i, v) in v.iter_mut().enumerate() {
                *v = round(*v, lane(&s[4 * i..]));
            }
        }
        v[0].rotate_left(1)
            .wrapping_add(v[1].rotate_left(7))
            .wrapping_add(v[2].rotate_left(12))
            .wrapping_add(v[3].rotate_left(18))
    } else {
        P5
    };
    acc = acc.wrapping_add(data.len() as u32);
    let mut words = stripes.remainder().chunks_exact(4);
    for w in &mut words {
        acc = acc
            .wrapping_add(lane(w).wrapping_mul(P3))
            .rotate_left(17)
            .wrapping_mul(P4);
    }
    for &b in words.remainder() {
        acc = acc
            .wrapping_add(u32::from(b).wrapping_mul(P5))
            .rotate_left(11)
            .wrapping_mul(P1);
    }
    acc ^= acc >> 15;
    acc = acc.wrapping_mul(P2);
    acc ^= acc >> 13;
    acc = acc.wrapping_mul(P3);
    acc ^ (acc >> 16)
}
