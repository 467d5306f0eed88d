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

use glam::Vec2;

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
    /// Per child, the child when it is a disc of constant elevation (the plateaus and
    /// hills that make most of a large blend), in a few packed bytes: the point query
    /// weighs these without a branch and without reading the child's node.
    flat: Vec<Option<FlatDisc>>,
}

/// A disc of constant elevation, flattened.
#[derive(Clone, Copy, Debug)]
struct FlatDisc {
    centre: Vec2,
    /// `r²`.
    r2: f32,
    /// The elevation.
    h: f32,
}

impl Blend {
    /// `(f(p), α(p))`: the children over `p`'s cell of the index, in the order of the
    /// children, so the sums are the same whichever path a query takes.
    #[inline]
    fn eval(&self, p: Vec2, lod: &Lod) -> Sample {
        let (mut s, mut fs) = (0.0f32, 0.0f32);
        let mut add = |i: usize| {
            // A flat disc adds `0` where it does not weigh: no support test needed.
            let (a, af) = match self.flat[i] {
                Some(d) => {
                    let a = disc_weight(p - d.centre, d.r2);
                    (a, a * d.h)
                }
                None => self.weigh(i, p, lod),
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

impl FlatDisc {
    fn of(c: &Node) -> Option<FlatDisc> {
        match &c.kind {
            Kind::Primitive(Primitive::Disc(Disc {
                centre,
                radius,
                elevation: ElevationFn::Constant(h),
            })) => Some(FlatDisc {
                centre: *centre,
                r2: radius * radius,
                h: *h,
            }),
            _ => None,
        }
    }
}

impl Node {
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
        let support = boxes.iter().fold(EMPTY_RECT, |a, b| rect_union(&a, b));
        Node {
            kind: Kind::Blend(Blend {
                base,
                index: GridIndex::new(&boxes),
                flat: children.iter().map(FlatDisc::of).collect(),
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
