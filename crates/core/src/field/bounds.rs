//! Boxes, intervals and the 2D footprints used by every bound in the field contract.

use glam::{Vec2, Vec3};

/// An axis-aligned box in metres. An *empty* box has `min > max` on some axis.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box spanning two corners given in any order.
    pub fn new(a: Vec3, b: Vec3) -> Self {
        Aabb {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// A cube of half-size `r` centred on `c`.
    pub fn around(c: Vec3, r: f32) -> Self {
        Aabb {
            min: c - Vec3::splat(r),
            max: c + Vec3::splat(r),
        }
    }

    /// The smallest box containing all `points`.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.include(p))
    }

    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// The box grown to contain `p`.
    pub fn include(self, p: Vec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Smallest box containing both.
    pub fn union(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// The common part (possibly empty).
    pub fn intersection(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// True when the boxes share at least one point.
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// True when `p` lies in the closed box.
    pub fn contains(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// True when `o` lies inside this box.
    pub fn contains_box(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && o.max.cmple(self.max).all()
    }

    /// The box grown by `r` on every side (shrunk for negative `r`).
    pub fn dilate(self, r: f32) -> Self {
        Aabb {
            min: self.min - Vec3::splat(r),
            max: self.max + Vec3::splat(r),
        }
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// Half the length of the diagonal: every point of the box is this close to the centre.
    pub fn radius(&self) -> f32 {
        self.size().length() * 0.5
    }

    /// The closest point of the box to `p`.
    pub fn clamp(&self, p: Vec3) -> Vec3 {
        p.clamp(self.min, self.max)
    }

    /// Euclidean distance from `p` to the box (0 inside).
    pub fn distance(&self, p: Vec3) -> f32 {
        (p - self.clamp(p)).length()
    }

    /// The box's footprint on the XY plane.
    pub fn footprint(&self) -> Rect {
        Rect {
            min: self.min.truncate(),
            max: self.max.truncate(),
        }
    }

    /// Its z extent.
    pub fn z(&self) -> Interval {
        Interval::new(self.min.z, self.max.z)
    }

    /// The 8 corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// Per-axis interval of the box.
    pub fn axis(&self, i: usize) -> Interval {
        Interval::new(self.min[i], self.max[i])
    }
}

/// A closed interval of reals `[lo, hi]`, used for sound range bounds.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Interval {
    /// Lower bound.
    pub lo: f32,
    /// Upper bound.
    pub hi: f32,
}

impl Interval {
    /// The empty interval: the identity of [`Interval::hull`].
    pub const EMPTY: Interval = Interval {
        lo: f32::INFINITY,
        hi: f32::NEG_INFINITY,
    };
    /// The interval `[0, 0]`.
    pub const ZERO: Interval = Interval { lo: 0.0, hi: 0.0 };

    /// `[lo, hi]` (the bounds are sorted).
    pub fn new(lo: f32, hi: f32) -> Self {
        Interval {
            lo: lo.min(hi),
            hi: lo.max(hi),
        }
    }

    /// The single value `v`.
    pub fn point(v: f32) -> Self {
        Interval { lo: v, hi: v }
    }

    /// True when `lo > hi`.
    pub fn is_empty(&self) -> bool {
        !(self.lo <= self.hi)
    }

    /// True when `v` is in the interval.
    pub fn contains(&self, v: f32) -> bool {
        self.lo <= v && v <= self.hi
    }

    /// Smallest interval holding both.
    pub fn hull(self, o: Interval) -> Self {
        Interval {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// Common part (possibly empty).
    pub fn intersect(self, o: Interval) -> Self {
        Interval {
            lo: self.lo.max(o.lo),
            hi: self.hi.min(o.hi),
        }
    }

    /// True when they share a point.
    pub fn overlaps(&self, o: &Interval) -> bool {
        self.lo <= o.hi && o.lo <= self.hi
    }

    /// `hi - lo`.
    pub fn width(&self) -> f32 {
        self.hi - self.lo
    }

    /// Midpoint.
    pub fn mid(&self) -> f32 {
        0.5 * (self.lo + self.hi)
    }

    /// Interval scaled by a constant.
    pub fn scale(self, k: f32) -> Self {
        Interval::new(self.lo * k, self.hi * k)
    }

    /// Interval shifted by a constant.
    pub fn shift(self, k: f32) -> Self {
        Interval {
            lo: self.lo + k,
            hi: self.hi + k,
        }
    }

    /// Pointwise maximum of two ranges.
    pub fn max(self, o: Interval) -> Self {
        Interval {
            lo: self.lo.max(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// Pointwise minimum of two ranges.
    pub fn min(self, o: Interval) -> Self {
        Interval {
            lo: self.lo.min(o.lo),
            hi: self.hi.min(o.hi),
        }
    }

    /// Range of `x²`.
    pub fn square(self) -> Self {
        if self.lo >= 0.0 {
            Interval::new(self.lo * self.lo, self.hi * self.hi)
        } else if self.hi <= 0.0 {
            Interval::new(self.hi * self.hi, self.lo * self.lo)
        } else {
            Interval::new(0.0, (self.lo * self.lo).max(self.hi * self.hi))
        }
    }

    /// The interval grown by `r` on both sides.
    pub fn dilate(self, r: f32) -> Self {
        Interval {
            lo: self.lo - r,
            hi: self.hi + r,
        }
    }
}

/// An axis-aligned rectangle of the XY plane: the footprint of a column of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Lower corner.
    pub min: Vec2,
    /// Upper corner.
    pub max: Vec2,
}

impl Rect {
    /// The rectangle spanning two corners given in any order.
    pub fn new(a: Vec2, b: Vec2) -> Self {
        Rect {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// The box `self × z`.
    pub fn extrude(&self, z: Interval) -> Aabb {
        Aabb {
            min: self.min.extend(z.lo),
            max: self.max.extend(z.hi),
        }
    }

    /// True when the rectangles share a point.
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// True when `o` lies inside.
    pub fn contains_rect(&self, o: &Rect) -> bool {
        self.min.cmple(o.min).all() && o.max.cmple(self.max).all()
    }

    /// Grown by `r` on every side.
    pub fn dilate(self, r: f32) -> Self {
        Rect {
            min: self.min - Vec2::splat(r),
            max: self.max + Vec2::splat(r),
        }
    }
}

/// A sorted list of disjoint z intervals: where a surface can lie over a footprint.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ZBands {
    bands: Vec<Interval>,
}

impl ZBands {
    /// No band at all: the surface does not cross this footprint.
    pub fn new() -> Self {
        ZBands { bands: Vec::new() }
    }

    /// Removes every band, keeping the allocation.
    pub fn clear(&mut self) {
        self.bands.clear();
    }

    /// Adds `z`, merging it with the bands it touches.
    pub fn push(&mut self, z: Interval) {
        if z.is_empty() {
            return;
        }
        let mut merged = z;
        self.bands.retain(|b| {
            if b.overlaps(&merged) {
                merged = merged.hull(*b);
                false
            } else {
                true
            }
        });
        let at = self.bands.partition_point(|b| b.hi < merged.lo);
        self.bands.insert(at, merged);
    }

    /// Adds all bands of `o`.
    pub fn extend(&mut self, o: &ZBands) {
        for b in &o.bands {
            self.push(*b);
        }
    }

    /// Keeps only the parts inside `z`.
    pub fn clip(&mut self, z: Interval) {
        for b in &mut self.bands {
            *b = b.intersect(z);
        }
        self.bands.retain(|b| !b.is_empty());
    }

    /// The bands, sorted and disjoint.
    pub fn as_slice(&self) -> &[Interval] {
        &self.bands
    }

    /// True when there is no band.
    pub fn is_empty(&self) -> bool {
        self.bands.is_empty()
    }

    /// True when `z` is inside some band.
    pub fn contains(&self, z: f32) -> bool {
        self.bands.iter().any(|b| b.contains(z))
    }
}

impl std::ops::Add for Interval {
    type Output = Interval;

    /// Interval sum.
    fn add(self, o: Interval) -> Self {
        Interval {
            lo: self.lo + o.lo,
            hi: self.hi + o.hi,
        }
    }
}

impl std::ops::Mul for Interval {
    type Output = Interval;

    /// Interval product.
    fn mul(self, o: Interval) -> Self {
        let c = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        Interval {
            lo: c.iter().copied().fold(f32::INFINITY, f32::min),
            hi: c.iter().copied().fold(f32::NEG_INFINITY, f32::max),
        }
    }
}
