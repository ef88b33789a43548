//! FAST-9 corners (Rosten & Drummond, ECCV 2006) with their score and a 3 × 3 non-maximum
//! suppression.
//!
//! A pixel `p` is a corner when at least 9 contiguous pixels of the 16-pixel Bresenham circle of
//! radius 3 around it are all brighter than `I_p + t` or all darker than `I_p − t`. Its score is
//! the paper's `V = max(Σ_{x ∈ S_bright} (|I_x − I_p| − t), Σ_{x ∈ S_dark} (|I_p − I_x| − t))`.

/// The 16 offsets `(dx, dy)` of the radius-3 Bresenham circle, clockwise from the top.
const CIRCLE: [(i32, i32); 16] = [
    (0, -3),
    (1, -3),
    (2, -2),
    (3, -1),
    (3, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 3),
    (-1, 3),
    (-2, 2),
    (-3, 1),
    (-3, 0),
    (-3, -1),
    (-2, -2),
    (-1, -3),
];

/// A corner in the pixel grid of one pyramid level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Corner {
    pub x: usize,
    pub y: usize,
    pub score: f32,
}

/// True when the 16-bit circular mask has a run of at least 9 set bits.
#[inline]
fn has_arc9(mask: u32) -> bool {
    // Doubling the mask turns the circular run into a linear one.
    let mut run = mask | (mask << 16);
    for _ in 0..8 {
        run &= run >> 1;
    }
    run != 0
}

/// FAST-9 score of the pixel at linear index `i`, `None` when it is not a corner.
#[inline]
fn corner_score(pixels: &[u8], i: usize, offsets: &[isize; 16], t: i32) -> Option<f32> {
    let p = i32::from(pixels[i]);
    let at = |k: usize| i32::from(pixels[i.wrapping_add_signed(offsets[k])]);
    // Quick rejection (Rosten & Drummond's high-speed test): an arc of 9 contains pixel 0 or
    // pixel 8, and at least two of the four compass pixels.
    let (top, bottom) = (at(0), at(8));
    if (top - p).abs() <= t && (bottom - p).abs() <= t {
        return None;
    }
    let (mut nb, mut nd) = (0, 0);
    for k in [0, 4, 8, 12] {
        let v = at(k);
        nb += i32::from(v > p + t);
        nd += i32::from(v < p - t);
    }
    if nb < 2 && nd < 2 {
        return None;
    }
    let (mut bright, mut dark) = (0u32, 0u32);
    let (mut sum_bright, mut sum_dark) = (0i32, 0i32);
    for k in 0..16 {
        let v = at(k);
        if v > p + t {
            bright |= 1 << k;
            sum_bright += v - p - t;
        } else if v < p - t {
            dark |= 1 << k;
            sum_dark += p - v - t;
        }
    }
    if has_arc9(bright) || has_arc9(dark) {
        Some(sum_bright.max(sum_dark) as f32)
    } else {
        None
    }
}

/// FAST-9 corners of a `width × height` image at least `margin ≥ 3` pixels from the border,
/// after 3 × 3 non-maximum suppression (a plateau keeps its first pixel in raster order).
/// `scores` is scratch space, resized here.
pub(crate) fn detect(
    pixels: &[u8],
    width: usize,
    height: usize,
    threshold: u8,
    margin: usize,
    scores: &mut Vec<f32>,
    out: &mut Vec<Corner>,
) {
    out.clear();
    let margin = margin.max(3);
    if width <= 2 * margin || height <= 2 * margin {
        return;
    }
    let w = width as isize;
    let offsets = CIRCLE.map(|(dx, dy)| dy as isize * w + dx as isize);
    let t = i32::from(threshold);
    scores.clear();
    scores.resize(width * height, 0.0);
    for y in margin..height - margin {
        for x in margin..width - margin {
            let i = y * width + x;
            if let Some(s) = corner_score(pixels, i, &offsets, t) {
                // +1 keeps a zero-sum corner distinct from "no corner".
                scores[i] = s + 1.0;
            }
        }
    }
    for y in margin..height - margin {
        for x in margin..width - margin {
            let i = y * width + x;
            let s = scores[i];
            if s > 0.0 && is_local_max(scores, i, width, s) {
                out.push(Corner { x, y, score: s });
            }
        }
    }
}

/// 3 × 3 maximum: strictly above the neighbours before `i` in raster order, at least equal to
/// those after it (deterministic on plateaus).
#[inline]
fn is_local_max(scores: &[f32], i: usize, width: usize, s: f32) -> bool {
    let before = [i - width - 1, i - width, i - width + 1, i - 1];
    let after = [i + 1, i + width - 1, i + width, i + width + 1];
    before.iter().all(|&j| scores[j] < s) && after.iter().all(|&j| scores[j] <= s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_detection_wraps_around() {
        assert!(has_arc9(0b1_1111_1111));
        assert!(!has_arc9(0b1111_1111));
        // 5 bits at the end and 4 at the start: contiguous through the wrap.
        assert!(has_arc9(0b1111_1000_0000_0000 | 0b1111 | (1 << 11)));
        assert!(!has_arc9(0b1010_1010_1010_1010));
    }

    #[test]
    fn square_corner_is_found_once() {
        // A bright square on a dark background: FAST fires at its four corners.
        let (w, h) = (40, 40);
        let mut img = vec![10u8; w * h];
        for y in 12..28 {
            for x in 12..28 {
                img[y * w + x] = 200;
            }
        }
        let (mut scores, mut out) = (Vec::new(), Vec::new());
        detect(&img, w, h, 20, 3, &mut scores, &mut out);
        assert_eq!(out.len(), 4, "{out:?}");
        for c in &out {
            let near = |a: usize, b: usize| a.abs_diff(b) <= 1;
            assert!((near(c.x, 12) || near(c.x, 27)) && (near(c.y, 12) || near(c.y, 27)));
        }
        // A flat image has none.
        detect(&vec![77u8; w * h], w, h, 20, 3, &mut scores, &mut out);
        assert!(out.is_empty());
    }
}
