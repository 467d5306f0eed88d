//! A sum of many Wyvill point blobs with local Lipschitz bounds from a uniform grid (the
//! segment-tracing scene).

use glam::Vec3;
use karstic::field::falloff::{WYVILL_MAX_SLOPE, wyvill, wyvill_d, wyvill_slope};
use karstic::field::{Aabb, Field, Interval};

use super::Rng;

/// `Σ e · g(|p − c_i| / R)` with a uniform grid of cell size `R`: each cell lists the
/// blobs whose support overlaps it (for values) and the blobs centred in it (for segment
/// bounds), and holds a bound of `|∇f|` inside it (for long segments and boxes).
pub struct Blobs {
    pub centers: Vec<Vec3>,
    pub energy: f32,
    pub radius: f32,
    origin: Vec3,
    dims: [i32; 3],
    starts: Vec<u32>,
    items: Vec<Vec3>,
    centered_starts: Vec<u32>,
    centered: Vec<Vec3>,
    slope: Vec<f32>,
}

impl Blobs {
    /// `n` blobs scattered uniformly in a ball of radius `ball`, each `energy · g(d / radius)`.
    pub fn in_ball(n: usize, ball: f32, radius: f32, energy: f32, seed: u64) -> Self {
        let mut rng = Rng(seed);
        let centers = (0..n).map(|_| rng.in_ball(ball)).collect();
        Blobs::new(centers, radius, energy)
    }

    pub fn new(centers: Vec<Vec3>, radius: f32, energy: f32) -> Self {
        assert!(energy > 0.0 && radius > 0.0);
        let b = Aabb::from_points(centers.iter().copied()).dilate(radius);
        let dims = ((b.size() / radius).ceil().as_ivec3().max(glam::IVec3::ONE)).to_array();
        let ncell = (dims[0] * dims[1] * dims[2]) as usize;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); ncell];
        let mut slope = vec![0.0f32; ncell];
        let k = energy / radius;
        for (i, c) in centers.iter().enumerate() {
            let lo = ((*c - radius - b.min) / radius)
                .floor()
                .as_ivec3()
                .max(glam::IVec3::ZERO);
            let hi = ((*c + radius - b.min) / radius)
                .floor()
                .as_ivec3()
                .min(glam::IVec3::from(dims) - 1);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let cell_min = b.min + Vec3::new(x as f32, y as f32, z as f32) * radius;
                        let cell = Aabb::new(cell_min, cell_min + radius);
                        let dlo = cell.distance(*c);
                        if dlo >= radius {
                            continue;
                        }
                        let dhi = cell
                            .corners()
                            .iter()
                            .map(|q| q.distance(*c))
                            .fold(0.0, f32::max);
                        let at = (x + dims[0] * (y + dims[1] * z)) as usize;
                        lists[at].push(i as u32);
                        slope[at] += k * wyvill_slope(Interval::new(dlo / radius, dhi / radius));
                    }
                }
            }
        }
        let csr = |lists: &[Vec<u32>]| {
            let mut starts = Vec::with_capacity(lists.len() + 1);
            let mut items = Vec::new();
            for l in lists {
                starts.push(items.len() as u32);
                items.extend(l.iter().map(|&i| centers[i as usize]));
            }
            starts.push(items.len() as u32);
            (starts, items)
        };
        let mut by_center: Vec<Vec<u32>> = vec![Vec::new(); ncell];
        for (i, c) in centers.iter().enumerate() {
            let q = ((*c - b.min) / radius)
                .floor()
                .as_ivec3()
                .clamp(glam::IVec3::ZERO, glam::IVec3::from(dims) - 1);
            by_center[(q.x + dims[0] * (q.y + dims[1] * q.z)) as usize].push(i as u32);
        }
        let (starts, items) = csr(&lists);
        let (centered_starts, centered) = csr(&by_center);
        Blobs {
            centers,
            energy,
            radius,
            origin: b.min,
            dims,
            starts,
            items,
            centered_starts,
            centered,
            slope,
        }
    }

    fn cell_of(&self, p: Vec3) -> Option<usize> {
        let q = (p - self.origin) / self.radius;
        if q.min_element() < 0.0 {
            return None;
        }
        // Non-negative: truncation is the floor (and avoids a libm call).
        let c = q.as_ivec3();
        let d = self.dims;
        if c.x >= d[0] || c.y >= d[1] || c.z >= d[2] {
            return None;
        }
        Some((c.x + d[0] * (c.y + d[1] * c.z)) as usize)
    }

    fn blobs_at(&self, p: Vec3) -> &[Vec3] {
        match self.cell_of(p) {
            Some(c) => &self.items[self.starts[c] as usize..self.starts[c + 1] as usize],
            None => &[],
        }
    }

    /// The value by brute force over every blob (the grid-free reference).
    pub fn value_brute(&self, p: Vec3) -> f32 {
        self.centers
            .iter()
            .map(|c| self.energy * wyvill(p.distance(*c) / self.radius))
            .sum()
    }

    fn cell_range(&self, b: &Aabb) -> Option<(glam::IVec3, glam::IVec3)> {
        let hi_cell = glam::IVec3::from(self.dims) - 1;
        let lo = ((b.min - self.origin) / self.radius).floor().as_ivec3();
        let hi = ((b.max - self.origin) / self.radius).floor().as_ivec3();
        if hi.cmplt(glam::IVec3::ZERO).any() || lo.cmpgt(hi_cell).any() {
            return None;
        }
        Some((lo.max(glam::IVec3::ZERO), hi.min(hi_cell)))
    }
}

impl Field for Blobs {
    fn value(&self, p: Vec3) -> f32 {
        let r2 = self.radius * self.radius;
        let mut v = 0.0;
        for c in self.blobs_at(p) {
            let d2 = p.distance_squared(*c);
            if d2 < r2 {
                let s = 1.0 - d2 / r2;
                v += s * s * s;
            }
        }
        self.energy * v
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (mut v, mut g) = (0.0, Vec3::ZERO);
        for c in self.blobs_at(p) {
            let d = p - *c;
            let l = d.length();
            let (w, dw) = wyvill_d(l / self.radius);
            v += w;
            if l > 0.0 {
                g += d / l * (dw / self.radius);
            }
        }
        (self.energy * v, self.energy * g)
    }
    fn support(&self) -> Aabb {
        Aabb::from_points(self.centers.iter().copied()).dilate(self.radius)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let hi = self
            .centers
            .iter()
            .map(|c| wyvill(b.distance(*c) / self.radius))
            .sum::<f32>();
        Interval::new(0.0, self.energy * hi)
    }
    /// What a blend node reports: the sum of its children's global bounds.
    fn lipschitz(&self) -> f32 {
        self.centers.len() as f32 * self.energy * WYVILL_MAX_SLOPE / self.radius
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let Some((lo, hi)) = self.cell_range(b) else {
            return 0.0;
        };
        let mut m = 0.0f32;
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    m = m.max(self.slope[(x + self.dims[0] * (y + self.dims[1] * z)) as usize]);
                }
            }
        }
        m
    }
    /// Short segments (up to `2R`): the sum over the blobs within reach of each blob's
    /// directional slope bound along the segment. Longer ones: the largest cell bound
    /// along the segment (pieces no longer than a cell, each covered by the cells its box
    /// overlaps).
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        let r = self.radius;
        let ab = b - a;
        let len2 = ab.length_squared();
        let (r2, inv_r) = (r * r, 1.0 / r);
        // Along the segment a blob is φ(s) = g(√((s − s₀)² + h²) / R) (h: distance from
        // the blob's centre to the line), so |φ'| = |g'(x)|·√(1 − k²/x²)/R with k = h/R:
        // 6(1 − y)²√(y − k²)/R in y = x², unimodal with its peak at y* = (1 + 4k²)/5. Its
        // maximum over the segment's range of y is a directional Lipschitz bound, which is
        // all the contract asks for pairs of points on the segment.
        let slope_on_segment = |c: Vec3| {
            let ac = c - a;
            let t = if len2 > 0.0 { ac.dot(ab) / len2 } else { 0.0 };
            let near2 = (ac - ab * t.clamp(0.0, 1.0)).length_squared();
            if near2 >= r2 {
                return 0.0;
            }
            let k2 = (ac - ab * t).length_squared() * inv_r * inv_r;
            let far2 = ac.length_squared().max((c - b).length_squared());
            let y = ((1.0 + 4.0 * k2) * 0.2)
                .clamp(near2 * inv_r * inv_r, (far2 * inv_r * inv_r).min(1.0));
            6.0 * (1.0 - y) * (1.0 - y) * (y - k2).max(0.0).sqrt()
        };
        let (ca, cb) = (self.cell_of(a), self.cell_of(b));
        if ca.is_some() && ca == cb {
            // Both ends in one (convex) cell: the blobs overlapping it are all that reach.
            let c = ca.unwrap_or_default();
            let list = &self.items[self.starts[c] as usize..self.starts[c + 1] as usize];
            return self.energy * inv_r * list.iter().map(|&c| slope_on_segment(c)).sum::<f32>();
        }
        if len2 <= 4.0 * r * r {
            let Some((lo, hi)) = self.cell_range(&Aabb::new(a, b).dilate(r)) else {
                return 0.0;
            };
            let mut sum = 0.0;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    let row = self.dims[0] * (y + self.dims[1] * z);
                    let (s, e) = (
                        self.centered_starts[(row + lo.x) as usize] as usize,
                        self.centered_starts[(row + hi.x + 1) as usize] as usize,
                    );
                    for &c in &self.centered[s..e] {
                        sum += slope_on_segment(c);
                    }
                }
            }
            return self.energy * inv_r * sum;
        }
        let n = (ab.abs().max_element() / r).ceil().max(1.0) as usize;
        let mut m = 0.0f32;
        let mut p = a;
        for i in 1..=n {
            let q = a.lerp(b, i as f32 / n as f32);
            m = m.max(self.lipschitz_box(&Aabb::new(p, q)));
            p = q;
        }
        m
    }
}
