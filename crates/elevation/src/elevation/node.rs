//! The nodes of an elevation tree and their evaluation (Génevaux et al. 2015 §3, §5).
//!
//! Every node maps a point `p ∈ R²` to an elevation `f` and a weight `α ≥ 0`. With
//! `a_B = min(α_B, 1)`:
//!
//! * **Blend** (§5.1), n-ary: `f = (Σ α_i f_i + (T − S)₊ b) / max(S, T)`, `S = Σ α_i`,
//!   `α = S`. Where `S ≥ T` this is the paper's `Σ α_i f_i / Σ α_i`; below the paper's
//!   threshold `T = ½` (its `Ω_T`) the missing weight goes to the blend's base elevation
//!   `b`, so `f` is defined, continuous and Lipschitz everywhere instead of only on `Ω_T`.
//! * **Add** (§5.3): `f = f_A + β a_B f_B`, `α = α_A`, where `β = b(size / ρ)` is the LoD
//!   filter of the added detail's size (1 without a size).
//! * **Replace** (§5.2): `f = (1 − a_B) f_A + a_B f_B`, `α = α_A`: continuous, since
//!   `a_B` is, and asymmetric.
//! * **Warp** (§5.4): `f(p) = f_C(ω(p))`, `α(p) = α_C(ω(p))` with the project's
//!   turbulence warp `ω` (`field::Warp`, Paris et al. 2019 §5.3) restricted to the plane.
//!
//! Bounds over a rectangle (ranges of `f` and `α`, Lipschitz bounds `λ_f`, `λ_α`) are in
//! `bounds.rs`.

use glam::{Vec2, Vec4};

use super::geometry::{EMPTY_RECT, rect_contains, rect_union};
use super::index::GridIndex;
use super::lod::Lod;
use super::multifractal::ElevationFn;
use super::primitive::{Disc, Primitive, Sample, disc_weight};
pub use crate::field::lanes::Lanes;
#[cfg(target_arch = "x86_64")]
use crate::field::lanes::{F8, has_avx2};
use crate::field::noise::NoiseLanes;
use crate::field::{Rect, Warp};

/// The blend's weight floor: the threshold `T = ½` of Génevaux et al. 2015 §3.
pub const BLEND_FLOOR: f32 = 0.5;

/// A node and the box outside which its weight is 0.
#[derive(Clone, Debug)]
pub struct Node {
    pub(super) kind: Kind,
    pub(super) support: Rect,
}

/// What a node does.
#[derive(Clone, Debug)]
pub(super) enum Kind {
    Primitive(Primitive),
    Blend(Blend),
    Add {
        a: Box<Node>,
        b: Box<Node>,
        size: Option<f32>,
    },
    Replace {
        a: Box<Node>,
        b: Box<Node>,
    },
    Warp {
        child: Box<Node>,
        warp: Warp,
    },
}

/// An n-ary blend.
#[derive(Clone, Debug)]
pub(super) struct Blend {
    pub(super) base: f32,
    pub(super) children: Vec<Node>,
    pub(super) index: Option<GridIndex>,
    /// Per child, `(centre, r², elevation)` for a disc — the elevation `NaN` when it is
    /// not constant — and `(0, 0, −1, NaN)` for any other child (a weight above 0 at
    /// every point). The point query weighs the discs of constant elevation (the plateaus
    /// and hills that make most of a large blend) without a branch and without reading the
    /// child's node, and reads the node of another disc only where its weight is not 0.
    discs: Vec<Vec4>,
}

impl Blend {
    /// `(f(p), α(p))`: the children over `p`'s cell of the index, in the order of the
    /// children, so the sums are the same whichever path a query takes.
    #[inline]
    fn eval(&self, p: Vec2, lod: &Lod) -> Sample {
        let (mut s, mut fs) = (0.0f32, 0.0f32);
        let mut add = |i: usize| {
            // A disc adds `0` where it does not weigh: no support test needed.
            let d = self.discs[i];
            let a = disc_weight(p - Vec2::new(d.x, d.y), d.z);
            let (a, af) = if !d.w.is_nan() {
                (a, a * d.w)
            } else if a > 0.0 {
                self.weigh(i, p, lod)
            } else {
                (0.0, 0.0)
            };
            s += a;
            fs += af;
        };
        match &self.index {
            Some(ix) => ix.at(p).iter().for_each(|&i| add(i as usize)),
            None => (0..self.children.len()).for_each(add),
        }
        let w = s.max(BLEND_FLOOR);
        Sample {
            f: (fs + (w - s) * self.base) / w,
            a: s,
        }
    }

    /// `out[k] = self.eval(points[k], lod).f` bit for bit, `L::N` points at a time on the
    /// lanes of SIMD registers. The points are sorted by their cell of the index (a
    /// counting sort), so the points of a cell share its list of candidates: for each
    /// candidate in the list's order, each lane adds its point's term to its sums with the
    /// same operations as [`Blend::eval`] — the candidate's data read once for all the
    /// cell's points, the points' sums in memory. A multifractal disc's elevation is
    /// evaluated only at the points it weighs at, `L::N` such points at a time
    /// (`Multifractal::values_lanes`).
    #[inline(always)]
    fn heights_lanes<L: NoiseLanes>(
        &self,
        ix: &GridIndex,
        points: &[Vec2],
        lod: &Lod,
        out: &mut [f32],
    ) {
        // The points off the grid (whose list is empty) go in one more cell.
        let cells = ix.cell_count();
        let keys: Vec<u32> = points
            .iter()
            .map(|&p| ix.cell(p).unwrap_or(cells) as u32)
            .collect();
        let mut start = vec![0u32; cells + 2];
        for &c in &keys {
            start[c as usize + 1] += 1;
        }
        for c in 1..start.len() {
            start[c] += start[c - 1];
        }
        // The points in the order of their cells, by coordinate, and where each came from.
        let mut next = start.clone();
        let (mut xs, mut ys) = (vec![0.0f32; points.len()], vec![0.0f32; points.len()]);
        let mut order = vec![0u32; points.len()];
        for (k, (&c, p)) in keys.iter().zip(points).enumerate() {
            let at = next[c as usize] as usize;
            (xs[at], ys[at], order[at]) = (p.x, p.y, k as u32);
            next[c as usize] += 1;
        }
        let mut lanes = CellPoints::<L>::default();
        let mut f = [0.0f32; MAX_LANES];
        for c in 0..=cells {
            let run = start[c] as usize..start[c + 1] as usize;
            if run.is_empty() {
                continue;
            }
            lanes.load(&xs[run.clone()], &ys[run.clone()]);
            let list = if c < cells { ix.list(c) } else { &[] };
            for &i in list {
                self.add_terms(i as usize, lod, &mut lanes);
            }
            for (g, group) in order[run].chunks(L::N).enumerate() {
                let (s, fs) = (lanes.s[g], lanes.fs[g]);
                let w = s.max(L::splat(BLEND_FLOOR));
                ((fs + (w - s) * L::splat(self.base)) / w).store(&mut f);
                for (&k, f) in group.iter().zip(f) {
                    out[k as usize] = f;
                }
            }
        }
    }

    /// [`Blend::heights_lanes`] on the eight lanes of AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn heights_avx2(&self, ix: &GridIndex, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
        self.heights_lanes::<F8>(ix, points, lod, out)
    }

    /// [`Blend::heights_lanes`] at the widest lanes this CPU runs: eight with AVX2, four
    /// otherwise — the same heights.
    fn heights(&self, ix: &GridIndex, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if has_avx2() {
            // SAFETY: the CPU has AVX2.
            return unsafe { self.heights_avx2(ix, points, lod, out) };
        }
        self.heights_lanes::<Vec4>(ix, points, lod, out)
    }

    /// Adds child `i`'s terms `(α, α f)` to the sums of the points in `lanes`: a disc of
    /// constant elevation from its entry in `discs`; a multifractal disc where its weight
    /// is not 0, its elevation at those points `L::N` at a time (the last few, four at a
    /// time); any other child by [`Blend::weigh`] where its entry does not weigh 0.
    #[inline(always)]
    fn add_terms<L: NoiseLanes>(&self, i: usize, lod: &Lod, lanes: &mut CellPoints<L>) {
        let d = self.discs[i];
        let (cx, cy, r2) = (L::splat(d.x), L::splat(d.y), L::splat(d.z));
        let n = lanes.x.len();
        if !d.w.is_nan() {
            let h = L::splat(d.w);
            for g in 0..n {
                let a = disc_weight_lanes(lanes.x[g] - cx, lanes.y[g] - cy, r2);
                lanes.s[g] += a;
                lanes.fs[g] += a * h;
            }
            return;
        }
        let child = &self.children[i];
        let fractal = match &child.kind {
            Kind::Primitive(Primitive::Disc(Disc {
                centre,
                elevation: ElevationFn::Fractal(m),
                ..
            })) => Some((*centre, m)),
            _ => None,
        };
        lanes.a.resize(n * L::N, 0.0);
        lanes.af.clear();
        lanes.af.resize(n * L::N, 0.0);
        lanes.pending.clear();
        let (mut x, mut y) = ([0.0f32; MAX_LANES], [0.0f32; MAX_LANES]);
        for g in 0..n {
            let a = &mut lanes.a[g * L::N..(g + 1) * L::N];
            disc_weight_lanes(lanes.x[g] - cx, lanes.y[g] - cy, r2).store(a);
            lanes.x[g].store(&mut x);
            lanes.y[g].store(&mut y);
            let af = &mut lanes.af[g * L::N..(g + 1) * L::N];
            // The lanes that repeat the last point are not evaluated: no output reads them.
            for l in 0..L::N.min(lanes.len - g * L::N) {
                if a[l] > 0.0 {
                    let p = Vec2::new(x[l], y[l]);
                    if fractal.is_some() && rect_contains(&child.support, p) {
                        lanes.pending.push((g * L::N + l, p));
                    } else {
                        (a[l], af[l]) = self.weigh(i, p, lod);
                    }
                }
            }
        }
        if let Some((centre, m)) = fractal {
            let mut f = [0.0f32; MAX_LANES];
            for some in lanes.pending.chunks(L::N) {
                for (l, (x, y)) in x.iter_mut().zip(&mut y).take(L::N).enumerate() {
                    let p = some[l.min(some.len() - 1)].1 - centre;
                    (*x, *y) = (p.x, p.y);
                }
                match some.len() {
                    1 => f[0] = m.value(some[0].1 - centre, lod),
                    2..=4 => m
                        .values_lanes(Vec4::from_slice(&x), Vec4::from_slice(&y), lod)
                        .store(&mut f),
                    _ => m.values_lanes(L::load(&x), L::load(&y), lod).store(&mut f),
                }
                for (&(k, _), f) in some.iter().zip(f) {
                    lanes.af[k] = lanes.a[k] * f;
                }
            }
        }
        for g in 0..n {
            lanes.s[g] += L::load(&lanes.a[g * L::N..]);
            lanes.fs[g] += L::load(&lanes.af[g * L::N..]);
        }
    }

    /// `(α, α f)` of child `i` at `p` (`(0, 0)` where it does not weigh), the elevation
    /// evaluated only where the weight is not 0.
    #[inline(never)]
    fn weigh(&self, i: usize, p: Vec2, lod: &Lod) -> (f32, f32) {
        let c = &self.children[i];
        if !rect_contains(&c.support, p) {
            return (0.0, 0.0);
        }
        let x = match &c.kind {
            Kind::Primitive(q) => q.eval_weighted(p, lod),
            _ => Some(c.eval(p, lod)).filter(|x| x.a > 0.0),
        };
        x.map_or((0.0, 0.0), |x| (x.a, x.a * x.f))
    }
}

/// The most lanes of [`Lanes`] a batch uses.
const MAX_LANES: usize = 8;

/// The disc weight of [`disc_weight`] on the lanes: `(1 − |q|²/r²)₊³` for the offsets
/// `(qx, qy)` from the centre, with the same operations as the point query.
#[inline(always)]
fn disc_weight_lanes<L: Lanes>(qx: L, qy: L, r2: L) -> L {
    let t = (L::ONE - (qx * qx + qy * qy) / r2).max(L::ZERO);
    t * t * t
}

/// The points of one cell of [`Blend::heights_lanes`], `L::N` to a group (a short last
/// group repeats its last point), and their sums; one child's terms per lane, and the
/// points where its elevation is still to be evaluated with their lane.
struct CellPoints<L> {
    x: Vec<L>,
    y: Vec<L>,
    s: Vec<L>,
    fs: Vec<L>,
    a: Vec<f32>,
    af: Vec<f32>,
    pending: Vec<(usize, Vec2)>,
    /// How many points (the lanes past them repeat the last one).
    len: usize,
}

impl<L> Default for CellPoints<L> {
    fn default() -> Self {
        CellPoints {
            x: Vec::new(),
            y: Vec::new(),
            s: Vec::new(),
            fs: Vec::new(),
            a: Vec::new(),
            af: Vec::new(),
            pending: Vec::new(),
            len: 0,
        }
    }
}

impl<L: Lanes> CellPoints<L> {
    /// The points `(xs[k], ys[k])` (at least one), with sums of 0.
    #[inline(always)]
    fn load(&mut self, xs: &[f32], ys: &[f32]) {
        let n = xs.len().div_ceil(L::N);
        let mut v = [0.0f32; MAX_LANES];
        for (to, from) in [(&mut self.x, xs), (&mut self.y, ys)] {
            to.clear();
            for g in 0..n {
                for (l, v) in v.iter_mut().take(L::N).enumerate() {
                    *v = from[(L::N * g + l).min(from.len() - 1)];
                }
                to.push(L::load(&v));
            }
        }
        self.s.clear();
        self.s.resize(n, L::ZERO);
        self.fs.clear();
        self.fs.resize(n, L::ZERO);
        self.len = xs.len();
    }
}

impl Node {
    /// The child's entry in [`Blend`]'s `discs`.
    fn flat_disc(&self) -> Vec4 {
        match &self.kind {
            Kind::Primitive(Primitive::Disc(Disc {
                centre,
                radius,
                elevation,
            })) => {
                let h = match elevation {
                    ElevationFn::Constant(h) if !h.is_nan() => *h,
                    _ => f32::NAN,
                };
                Vec4::new(centre.x, centre.y, radius * radius, h)
            }
            _ => Vec4::new(0.0, 0.0, -1.0, f32::NAN),
        }
    }

    /// `(centre, radius)` of a disc primitive.
    fn disc(&self) -> Option<(Vec2, f32)> {
        match &self.kind {
            Kind::Primitive(Primitive::Disc(d)) => Some((d.centre, d.radius)),
            _ => None,
        }
    }

    /// `out[k] = self.eval(points[k], lod).f`: a blend with an index on SIMD lanes
    /// ([`Blend::heights_lanes`]), any other node point by point.
    pub(super) fn heights(&self, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
        match &self.kind {
            Kind::Blend(
                b @ Blend {
                    index: Some(ix), ..
                },
            ) => b.heights(ix, points, lod, out),
            _ => {
                for (o, p) in out.iter_mut().zip(points) {
                    *o = self.eval(*p, lod).f;
                }
            }
        }
    }

    /// A primitive leaf.
    pub fn primitive(p: Primitive) -> Node {
        Node {
            support: p.support(),
            kind: Kind::Primitive(p),
        }
    }

    /// The blend of `children` over the base elevation `base`.
    pub fn blend(base: f32, children: Vec<Node>) -> Node {
        let boxes: Vec<Rect> = children.iter().map(|c| c.support).collect();
        let discs: Vec<Option<(Vec2, f32)>> = children.iter().map(Node::disc).collect();
        let support = boxes.iter().fold(EMPTY_RECT, |a, b| rect_union(&a, b));
        Node {
            kind: Kind::Blend(Blend {
                base,
                index: GridIndex::new(&boxes, &discs),
                discs: children.iter().map(Node::flat_disc).collect(),
                children,
            }),
            support,
        }
    }

    /// `b` added to `a` where `b` weighs; `size` (metres) is the detail's size for LoD.
    pub fn add(a: Node, b: Node, size: Option<f32>) -> Node {
        Node {
            support: a.support,
            kind: Kind::Add {
                a: Box::new(a),
                b: Box::new(b),
                size,
            },
        }
    }

    /// `a` replaced by `b` where `b` weighs.
    pub fn replace(a: Node, b: Node) -> Node {
        Node {
            support: a.support,
            kind: Kind::Replace {
                a: Box::new(a),
                b: Box::new(b),
            },
        }
    }

    /// `child` warped by `warp` (evaluated in the plane `z = 0`).
    pub fn warp(child: Node, warp: Warp) -> Node {
        Node {
            support: child.support.dilate(warp.reach()),
            kind: Kind::Warp {
                child: Box::new(child),
                warp,
            },
        }
    }

    /// The box outside which `α = 0`.
    pub fn support(&self) -> Rect {
        self.support
    }

    /// `(f(p), α(p))` at level of detail `lod`.
    pub fn eval(&self, p: Vec2, lod: &Lod) -> Sample {
        match &self.kind {
            Kind::Primitive(q) => q.eval(p, lod),
            Kind::Blend(b) => b.eval(p, lod),
            Kind::Add { a, b, size } => {
                let x = a.eval(p, lod);
                let beta = size.map_or(1.0, |s| lod.filter(s));
                if beta == 0.0 || !rect_contains(&b.support, p) {
                    return x;
                }
                let y = b.eval(p, lod);
                Sample {
                    f: x.f + beta * y.a.min(1.0) * y.f,
                    a: x.a,
                }
            }
            Kind::Replace { a, b } => {
                let x = a.eval(p, lod);
                if !rect_contains(&b.support, p) {
                    return x;
                }
                let y = b.eval(p, lod);
                let w = y.a.min(1.0);
                Sample {
                    f: x.f + w * (y.f - x.f),
                    a: x.a,
                }
            }
            Kind::Warp { child, warp } => child.eval(warp.apply(p.extend(0.0)).truncate(), lod),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elevation::multifractal::{Kind as Fractal, Multifractal};

    /// The batch at four lanes, at the widest lanes this CPU has (eight with AVX2), and
    /// the point query give the same bits, multifractal discs of every kind and a nested
    /// blend among the children, at points inside, outside and not finite.
    #[test]
    fn every_lane_width_gives_the_point_query_bit_for_bit() {
        let mut seed = 7u32;
        let mut f = move || {
            seed = seed.wrapping_add(0x9e37_79b9);
            (crate::field::noise::mix32(seed) >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut disc = |k: u32| {
            let centre = Vec2::new(f() * 1000.0, f() * 1000.0);
            let radius = 40.0 + 120.0 * f();
            let elevation = match k % 4 {
                0 => ElevationFn::Fractal(Multifractal::new(Fractal::Fbm, 50.0, 80.0, 90.0, 3, k)),
                1 => {
                    ElevationFn::Fractal(Multifractal::new(Fractal::Ridged, 60.0, 90.0, 70.0, 5, k))
                }
                2 => {
                    ElevationFn::Fractal(Multifractal::new(Fractal::Hybrid, 40.0, 70.0, 80.0, 9, k))
                }
                _ => ElevationFn::Constant(200.0 * f()),
            };
            Node::primitive(Primitive::Disc(Disc {
                centre,
                radius,
                elevation,
            }))
        };
        let mut children: Vec<Node> = (0..80).map(&mut disc).collect();
        children.insert(9, Node::blend(30.0, (80..88).map(&mut disc).collect()));
        let root = Node::blend(40.0, children);
        let Kind::Blend(
            b @ Blend {
                index: Some(ix), ..
            },
        ) = &root.kind
        else {
            panic!("the blend has no index");
        };
        let mut points: Vec<Vec2> = (0..30_000)
            .map(|_| Vec2::new(f() * 1400.0 - 200.0, f() * 1400.0 - 200.0))
            .collect();
        points.extend([Vec2::NAN, Vec2::new(f32::INFINITY, 5.0), Vec2::splat(-1e9)]);
        for lod in [Lod::FULL, Lod::new(3.0)] {
            let (mut four, mut widest) = (vec![0.0; points.len()], vec![0.0; points.len()]);
            b.heights_lanes::<Vec4>(ix, &points, &lod, &mut four);
            root.heights(&points, &lod, &mut widest);
            for (k, p) in points.iter().enumerate() {
                let want = root.eval(*p, &lod).f.to_bits();
                assert_eq!(four[k].to_bits(), want, "4 lanes at {p}");
                assert_eq!(widest[k].to_bits(), want, "widest lanes at {p}");
            }
        }
    }
}
