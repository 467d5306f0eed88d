//! A min/max pyramid over grid cells: conservative ranges over any cell rectangle in O(1).
//!
//! Level 0 holds one `[lo, hi]` per cell (or, with `N > 2` channels, a range followed by
//! further values merged by their maximum: the heightfield leaf keeps its elevation
//! range, slope bound and detail reach per cell in one pyramid, so one query answers all
//! three); level `k + 1` merges 2×2 blocks of level `k`. A
//! query picks the finest level at which the rectangle spans at most 4 blocks per axis and
//! merges those (≤ 16 lookups). The answer contains the exact range of the rectangle and is
//! exact when the rectangle is block-aligned at that level (always for ≤ 4×4 cells).

use crate::field::Interval;

/// Pyramid of `[lo, hi]` ranges; `[+∞, −∞]` marks a cell with no value. With `N`
/// channels, channel 0 merges by minimum and the others by maximum.
#[derive(Clone, Debug)]
pub struct MinMaxPyramid<const N: usize = 2> {
    levels: Vec<Level<N>>,
}

#[derive(Clone, Debug)]
struct Level<const N: usize> {
    w: usize,
    h: usize,
    data: Vec<[f32; N]>,
}

#[inline]
fn merge<const N: usize>(a: [f32; N], b: [f32; N]) -> [f32; N] {
    std::array::from_fn(|k| {
        if k == 0 {
            a[0].min(b[0])
        } else {
            a[k].max(b[k])
        }
    })
}

/// The merge's identity: `[+∞, −∞, …]`.
#[inline]
fn empty<const N: usize>() -> [f32; N] {
    std::array::from_fn(|k| {
        if k == 0 {
            f32::INFINITY
        } else {
            f32::NEG_INFINITY
        }
    })
}

impl<const N: usize> MinMaxPyramid<N> {
    /// Builds the pyramid over a `w × h` grid of cell values (row-major).
    ///
    /// # Panics
    /// When `cells.len() != w · h` or the grid is empty (a programming error).
    pub fn new(w: usize, h: usize, cells: Vec<[f32; N]>) -> MinMaxPyramid<N> {
        assert!(
            w > 0 && h > 0 && cells.len() == w * h,
            "pyramid of {w}×{h} needs {} cells",
            w * h
        );
        let mut levels = vec![Level { w, h, data: cells }];
        while let Some(l) = levels.last().filter(|l| l.w > 1 || l.h > 1) {
            let (w2, h2) = (l.w.div_ceil(2), l.h.div_ceil(2));
            let mut data = vec![empty(); w2 * h2];
            for j in 0..l.h {
                for i in 0..l.w {
                    let d = &mut data[i / 2 + w2 * (j / 2)];
                    *d = merge(*d, l.data[i + l.w * j]);
                }
            }
            levels.push(Level { w: w2, h: h2, data });
        }
        MinMaxPyramid { levels }
    }

    /// Cells along x and y at level 0.
    pub fn dims(&self) -> (usize, usize) {
        (self.levels[0].w, self.levels[0].h)
    }

    /// Range of one cell.
    #[inline]
    pub fn cell(&self, i: usize, j: usize) -> [f32; N] {
        let l = &self.levels[0];
        l.data[i + l.w * j]
    }

    /// The range over the whole grid (`[+∞, −∞]` when no cell has a value).
    pub fn total(&self) -> [f32; N] {
        self.levels.last().map_or(empty(), |l| l.data[0])
    }

    /// A range containing the ranges of cells `i0..=i1 × j0..=j1` (indices clamped).
    #[inline]
    pub fn query(&self, i0: usize, i1: usize, j0: usize, j1: usize) -> [f32; N] {
        let (w, h) = self.dims();
        let (i1, j1) = (i1.min(w - 1), j1.min(h - 1));
        if i0 > i1 || j0 > j1 {
            return empty();
        }
        let span = (i1 - i0).max(j1 - j0);
        // smallest k with (i1 >> k) - (i0 >> k) ≤ 3: start from the span's magnitude
        let mut k = (usize::BITS - (span / 4).leading_zeros()) as usize;
        while k > 0
            && (i1 >> (k - 1)) - (i0 >> (k - 1)) <= 3
            && (j1 >> (k - 1)) - (j0 >> (k - 1)) <= 3
        {
            k -= 1;
        }
        while (i1 >> k) - (i0 >> k) > 3 || (j1 >> k) - (j0 >> k) > 3 {
            k += 1;
        }
        let l = &self.levels[k.min(self.levels.len() - 1)];
        let mut r = empty();
        for j in (j0 >> k)..=(j1 >> k).min(l.h - 1) {
            for i in (i0 >> k)..=(i1 >> k).min(l.w - 1) {
                r = merge(r, l.data[i + l.w * j]);
            }
        }
        r
    }

    /// Channels 0 and 1 of [`MinMaxPyramid::query`] as an [`Interval`] (empty when no
    /// cell has a value).
    #[inline]
    pub fn query_interval(&self, i0: usize, i1: usize, j0: usize, j1: usize) -> Interval {
        let q = self.query(i0, i1, j0, j1);
        Interval { lo: q[0], hi: q[1] }
    }

    /// The levels, finest first: `(w, h, ranges)` with `ranges[i + w·j]` the range of
    /// block `(i, j)` (`2^k × 2^k` cells at level `k`, so `w = ⌈w₀ / 2^k⌉`).
    pub fn levels(&self) -> impl Iterator<Item = (usize, usize, &[[f32; N]])> {
        self.levels.iter().map(|l| (l.w, l.h, l.data.as_slice()))
    }

    /// Bytes held.
    pub fn memory(&self) -> usize {
        self.levels.iter().map(|l| l.data.len() * 4 * N).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EMPTY: [f32; 2] = [f32::INFINITY, f32::NEG_INFINITY];

    #[test]
    fn queries_contain_the_exact_range_and_are_exact_when_small() {
        let (w, h) = (37, 23);
        let mut seed = 11u64;
        let cells: Vec<[f32; 2]> = (0..w * h)
            .map(|k| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                if k % 17 == 5 {
                    return EMPTY;
                }
                let v = (seed >> 40) as f32 / 1e5;
                [v, v + (k % 3) as f32]
            })
            .collect();
        let p = MinMaxPyramid::new(w, h, cells.clone());
        let mut loose = 0;
        for i0 in (0..w).step_by(3) {
            for i1 in (i0..w).step_by(4) {
                for j0 in (0..h).step_by(2) {
                    for j1 in (j0..h).step_by(5) {
                        let mut exact = EMPTY;
                        for j in j0..=j1 {
                            for i in i0..=i1 {
                                exact = merge(exact, cells[i + w * j]);
                            }
                        }
                        let q = p.query(i0, i1, j0, j1);
                        assert!(q[0] <= exact[0] && q[1] >= exact[1]);
                        if i1 - i0 < 4 && j1 - j0 < 4 {
                            assert_eq!(q, exact);
                        }
                        loose += (q != exact) as usize;
                    }
                }
            }
        }
        assert!(loose > 0, "big queries are allowed to be conservative");
        assert_eq!(p.query(0, w - 1, 0, h - 1), p.total());
        assert_eq!(p.query(5, 4, 0, 0), EMPTY);
    }

    #[test]
    fn channels_merge_like_pyramids_of_their_own() {
        let (w, h) = (19, 13);
        let cell = |k: usize| {
            let v = ((k * 7919) % 101) as f32;
            [v, v + 3.0, (k % 11) as f32, ((k * 13) % 17) as f32]
        };
        let four = MinMaxPyramid::new(w, h, (0..w * h).map(cell).collect());
        let range =
            MinMaxPyramid::new(w, h, (0..w * h).map(|k| [cell(k)[0], cell(k)[1]]).collect());
        let maxima = |c: usize| {
            MinMaxPyramid::new(w, h, (0..w * h).map(|k| [cell(k)[c], cell(k)[c]]).collect())
        };
        let (m2, m3) = (maxima(2), maxima(3));
        for (i0, i1, j0, j1) in [(0, 18, 0, 12), (3, 9, 2, 11), (5, 5, 7, 7), (1, 17, 4, 6)] {
            let q = four.query(i0, i1, j0, j1);
            let want = range.query(i0, i1, j0, j1);
            assert_eq!([q[0], q[1]], want);
            assert_eq!(q[2], m2.query(i0, i1, j0, j1)[1]);
            assert_eq!(q[3], m3.query(i0, i1, j0, j1)[1]);
        }
        assert_eq!(four.memory(), 2 * range.memory());
    }
}
