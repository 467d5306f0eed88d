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

    /// `out[k] = self.eval(points[k], lod).f` bit for bit, four points at a time on the
    /// lanes of SIMD registers. The points are sorted by their cell of the index (a
    /// counting sort), so the points of a cell share its list of candidates: for each
    /// candidate in the list's order, each lane adds its point's term to its sums with the
    /// same operations as [`Blend::eval`] — the candidate's data read once for all the
    /// cell's points, the points' sums in memory. A multifractal disc's elevation is
    /// evaluated only at the points it weighs at, four such points at a time
    /// (`Multifractal::values4`).
    fn heights(&self, ix: &GridIndex, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
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
        let mut lanes = Lanes::default();
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
            for (g, group) in order[run].chunks(4).enumerate() {
                let (s, fs) = (lanes.s[g], lanes.fs[g]);
                let w = s.max(Vec4::splat(BLEND_FLOOR));
                let f = ((fs + (w - s) * self.base) / w).to_array();
                for (&k, f) in group.iter().zip(f) {
                    out[k as usize] = f;
                }
            }
        }
    }

    /// Adds child `i`'s terms `(α, α f)` to the sums of the points in `lanes`: a disc of
    /// constant elevation from its entry in `discs`; a multifractal disc where its weight
    /// is not 0, its elevation at those points four at a time; any other child by
    /// [`Blend::weigh`] where its entry does not weigh 0.
    #[inline]
    fn add_terms(&self, i: usize, lod: &Lod, lanes: &mut Lanes) {
        let d = self.discs[i];
        let (cx, cy, r2) = (Vec4::splat(d.x), Vec4::splat(d.y), Vec4::splat(d.z));
        let weight = |x: Vec4, y: Vec4| {
            let (qx, qy) = (x - cx, y - cy);
            let t = (Vec4::ONE - (qx * qx + qy * qy) / r2).max(Vec4::ZERO);
            t * t * t
        };
        let n = lanes.x.len();
        if !d.w.is_nan() {
            let h = Vec4::splat(d.w);
            for g in 0..n {
                let a = weight(lanes.x[g], lanes.y[g]);
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
        lanes.a.clear();
        lanes.af.clear();
        lanes.pending.clear();
        for g in 0..n {
            let (x, y) = (lanes.x[g].to_array(), lanes.y[g].to_array());
            let mut a = weight(lanes.x[g], lanes.y[g]).to_array();
            let mut af = [0.0f32; 4];
            for (l, (a, af)) in a.iter_mut().zip(&mut af).enumerate() {
                if *a > 0.0 {
                    let p = Vec2::new(x[l], y[l]);
                    if fractal.is_some() && rect_contains(&child.support, p) {
                        lanes.pending.push((g, l, p));
                    } else {
                        (*a, *af) = self.weigh(i, p, lod);
                    }
                }
            }
            lanes.a.push(a);
            lanes.af.push(af);
        }
        if let Some((centre, m)) = fractal {
            for four in lanes.pending.chunks(4) {
                let f = if let [(_, _, p)] = four {
                    [m.value(*p - centre, lod); 4]
                } else {
                    let p = |j: usize| four[j.min(four.len() - 1)].2 - centre;
                    let p: [Vec2; 4] = std::array::from_fn(p);
                    let (x, y) = (p.map(|p| p.x), p.map(|p| p.y));
                    m.values4(Vec4::from_array(x), Vec4::from_array(y), lod)
                        .to_array()
                };
                for (&(g, l, _), f) in four.iter().zip(f) {
                    lanes.af[g][l] = lanes.a[g][l] * f;
                }
            }
        }
        for g in 0..n {
            lanes.s[g] += Vec4::from_array(lanes.a[g]);
            lanes.fs[g] += Vec4::from_array(lanes.af[g]);
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

/// The points of one cell of [`Blend::heights`], four to a group (a short last group
/// repeats its last point), and their sums; one child's terms, and the points where its
/// elevation is still to be evaluated with their group and lane.
#[derive(Default)]
struct Lanes {
    x: Vec<Vec4>,
    y: Vec<Vec4>,
    s: Vec<Vec4>,
    fs: Vec<Vec4>,
    a: Vec<[f32; 4]>,
    af: Vec<[f32; 4]>,
    pending: Vec<(usize, usize, Vec2)>,
}

impl Lanes {
    /// The points `(xs[k], ys[k])` (at least one), with sums of 0.
    fn load(&mut self, xs: &[f32], ys: &[f32]) {
        let group = |v: &[f32], g: usize| {
            Vec4::from_array(std::array::from_fn(|l| v[(4 * g + l).min(v.len() - 1)]))
        };
        let n = xs.len().div_ceil(4);
        self.x.clear();
        self.x.extend((0..n).map(|g| group(xs, g)));
        self.y.clear();
        self.y.extend((0..n).map(|g| group(ys, g)));
        self.s.clear();
        self.s.resize(n, Vec4::ZERO);
        self.fs.clear();
        self.fs.resize(n, Vec4::ZERO);
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

    /// `out[k] = self.eval(points[k], lod).f`: a blend with an index four points at a time
    /// ([`Blend::heights`]), any other node point by point.
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
