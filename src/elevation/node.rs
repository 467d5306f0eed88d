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

use glam::{Mat4, Vec2, Vec4};

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
    /// Then one more entry, [`NO_DISC`], which weighs 0 at every point.
    discs: Vec<Vec4>,
}

/// A flat disc at infinity: `(1 − ∞ / 1)₊³ = 0` at every finite point.
const NO_DISC: Vec4 = Vec4::new(f32::INFINITY, f32::INFINITY, 1.0, 0.0);

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
    /// lanes of SIMD registers: lane `l` sums its own point's candidates in their order,
    /// with the same operations as [`Blend::eval`] (a lane past the end of its list adds
    /// [`NO_DISC`]'s zeros, which leave the sums as they are). The points are taken in
    /// order of their candidates' count, so the four of a group have about as many. Per
    /// group, the terms `(α, α f)` of the discs first, then those of the other children
    /// where they weigh, then the sums.
    fn heights(&self, ix: &GridIndex, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
        let items = ix.items();
        let lists: Vec<&[u32]> = points.iter().map(|&p| &items[ix.span(p)]).collect();
        // A counting sort of the points by their count.
        let longest = lists.iter().map(|l| l.len()).max().unwrap_or(0);
        let mut next = vec![0usize; longest + 2];
        for l in &lists {
            next[l.len() + 1] += 1;
        }
        for n in 1..next.len() {
            next[n] += next[n - 1];
        }
        let mut order = vec![0usize; points.len()];
        for (k, l) in lists.iter().enumerate() {
            order[next[l.len()]] = k;
            next[l.len()] += 1;
        }
        let none = self.children.len();
        let mut terms: Vec<[Vec4; 2]> = Vec::with_capacity(longest);
        let mut others: Vec<(usize, usize, usize)> = Vec::new();
        for group in order.chunks(4) {
            // A short last group repeats its last point.
            let ks: [usize; 4] = std::array::from_fn(|l| group[l.min(group.len() - 1)]);
            let p = ks.map(|k| points[k]);
            let (px, py) = (
                Vec4::from_array(p.map(|p| p.x)),
                Vec4::from_array(p.map(|p| p.y)),
            );
            let l = ks.map(|k| lists[k]);
            let steps = l.iter().map(|l| l.len()).max().unwrap_or(0);
            terms.clear();
            others.clear();
            for step in 0..steps {
                let c = l.map(|l| l.get(step).map_or(none, |&i| i as usize));
                let d = Mat4::from_cols(
                    self.discs[c[0]],
                    self.discs[c[1]],
                    self.discs[c[2]],
                    self.discs[c[3]],
                )
                .transpose();
                let (qx, qy) = (px - d.x_axis, py - d.y_axis);
                let t = (Vec4::ONE - (qx * qx + qy * qy) / d.z_axis).max(Vec4::ZERO);
                let a = t * t * t;
                let flat = d.w_axis.cmpeq(d.w_axis);
                terms.push([a, Vec4::select(flat, a * d.w_axis, Vec4::ZERO)]);
                let other = (!flat & a.cmpgt(Vec4::ZERO)).bitmask();
                if other != 0 {
                    for lane in (0..4).filter(|lane| other >> lane & 1 != 0) {
                        others.push((step, lane, c[lane]));
                    }
                }
            }
            for &(step, lane, c) in &others {
                let (a, af) = self.weigh(c, p[lane], lod);
                terms[step][0][lane] = a;
                terms[step][1][lane] = af;
            }
            let (s, fs) = terms
                .iter()
                .fold((Vec4::ZERO, Vec4::ZERO), |(s, fs), t| (s + t[0], fs + t[1]));
            let w = s.max(Vec4::splat(BLEND_FLOOR));
            let f = ((fs + (w - s) * self.base) / w).to_array();
            for (&k, f) in group.iter().zip(f) {
                out[k] = f;
            }
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
                discs: children
                    .iter()
                    .map(Node::flat_disc)
                    .chain([NO_DISC])
                    .collect(),
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
