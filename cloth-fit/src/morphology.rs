//! Binary morphology on masks: erosion and dilation by a (2r+1)² square, opening, closing, and
//! the largest 4-connected component (spec §3.4 step 6, §3.5 validity).

use geom_core::image::Mask;

/// Dilation by a (2r+1) × (2r+1) square (separable running max; outside the image is clear).
pub fn dilate(m: &Mask, r: u32) -> Mask {
    morph(m, r, true)
}

/// Erosion by a (2r+1) × (2r+1) square (outside the image counts as clear, so the border
/// erodes too).
pub fn erode(m: &Mask, r: u32) -> Mask {
    morph(m, r, false)
}

/// Opening (erode then dilate).
pub fn open(m: &Mask, r: u32) -> Mask {
    dilate(&erode(m, r), r)
}

/// Closing (dilate then erode). Pixels near the border may close only partially, since outside
/// counts as clear for the erosion.
pub fn close(m: &Mask, r: u32) -> Mask {
    erode(&dilate(m, r), r)
}

fn morph(m: &Mask, r: u32, dilate: bool) -> Mask {
    if r == 0 {
        return m.clone();
    }
    let (w, h) = (m.width as usize, m.height as usize);
    let r = r as usize;
    let pass = |src: &[bool], len: usize, stride: usize, lines: usize, lstride: usize| -> Vec<bool> {
        let mut out = vec![false; src.len()];
        for l in 0..lines {
            let base = l * lstride;
            // Prefix counts along the line.
            let mut pre = vec![0u32; len + 1];
            for i in 0..len {
                pre[i + 1] = pre[i] + src[base + i * stride] as u32;
            }
            for i in 0..len {
                let lo = i.saturating_sub(r);
                let hi = (i + r + 1).min(len);
                let count = pre[hi] - pre[lo];
                out[base + i * stride] = if dilate {
                    count > 0
                } else {
                    // Out-of-image pixels count as clear.
                    count as usize == 2 * r + 1 && i >= r && i + r < len
                };
            }
        }
        out
    };
    let a = pass(&m.data, w, 1, h, w);
    let b = pass(&a, h, w, w, 1);
    Mask { width: m.width, height: m.height, data: b }
}

/// The largest 4-connected component of set pixels (ties: the one met first in row-major
/// order); an empty mask stays empty.
pub fn largest_component(m: &Mask) -> Mask {
    let (w, h) = (m.width as usize, m.height as usize);
    let mut label = vec![0u32; w * h];
    let (mut best, mut best_size, mut next) = (0u32, 0usize, 0u32);
    let mut stack = Vec::new();
    for start in 0..w * h {
        if !m.data[start] || label[start] != 0 {
            continue;
        }
        next += 1;
        label[start] = next;
        stack.push(start);
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if m.data[j] && label[j] == 0 {
                    label[j] = next;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
        if size > best_size {
            best_size = size;
            best = next;
        }
    }
    Mask { width: m.width, height: m.height, data: label.iter().map(|&l| l != 0 && l == best).collect() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(w: u32, h: u32, x0: u32, y0: u32, x1: u32, y1: u32) -> Mask {
        let mut m = Mask::new(w, h, false);
        for y in y0..=y1 {
            for x in x0..=x1 {
                m.set(x, y, true);
            }
        }
        m
    }

    #[test]
    fn erosion_dilation_and_components() {
        let m = square(20, 20, 5, 5, 14, 14);
        assert_eq!(erode(&m, 2), square(20, 20, 7, 7, 12, 12));
        assert_eq!(dilate(&m, 1), square(20, 20, 4, 4, 15, 15));
        assert_eq!(open(&m, 1), m);
        let mut holes = m.clone();
        holes.set(9, 9, false);
        assert_eq!(close(&holes, 1), m);
        let mut two = m.clone();
        two.set(0, 0, true);
        assert_eq!(largest_component(&two), m);
        // Border pixels erode (outside counts as clear).
        assert_eq!(erode(&Mask::new(5, 5, true), 1), square(5, 5, 1, 1, 3, 3));
    }
}
