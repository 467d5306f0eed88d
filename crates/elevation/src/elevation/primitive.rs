//! The primitives of elevation trees (Génevaux et al. 2015 §4): each defines an elevation
//! `f: R² → R` everywhere and a weight `α = g(d / R) ∈ [0, 1]` (Wyvill's `g`) of compact
//! support, with a global range and Lipschitz bounds of both.
//!
//! * **Disc** (§4.1): `f(p) = h(p − c)` with `h` an [`ElevationFn`], `α = g(|p − c| / r)`.
//! * **Curve** (§4.1, rivers, ridges, roads): a polyline `Γ` of points `(x, y, z)` and a
//!   cross-section profile `c`; for each segment `i`, `f_i(p) = z_i(p) + c(d_i(p))` with
//!   `z_i` the elevation of the segment at the projection of `p` and `d_i` the distance to
//!   the segment. The paper's `f = q_z + c(d)` takes the nearest segment, which jumps across
//!   the medial axis inside a bend; we take `min_i f_i` for a valley profile and `max_i f_i`
//!   for a ridge, which agrees with it near the curve, is continuous everywhere, and is
//!   Lipschitz with `max_i |Δz_i| / |Δxy_i| + λ_c`. `α = g(d / R)`, `d = min_i d_i`.
//! * **Contour** (§4.1, lakes, plateaus): a polygon, an elevation `z` and a profile of the
//!   signed distance `s` to the contour (negative inside): `f = z + c(s)`,
//!   `α = g(max(s, 0) / R)`. The paper's radial profiles about a centre are not Lipschitz
//!   for contours that are not star-shaped about it; `s` is 1-Lipschitz for any polygon.
//! * **Image** (§4.2): a raster `H` over a rectangle, bilinear, clamped at its border;
//!   `α = g(max(0, R − e(p)) / R)` with `e` the clearance in the rectangle, so it is 1
//!   further than `R` inside and 0 on the border. `λ_f` is the steepest cell
//!   (§7.3.1).

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::geometry::{clearance, polygon_signed_distance, rect_centre, segment_distance};
use super::lod::Lod;
use super::multifractal::ElevationFn;
use super::profile::Profile;
use crate::dem::{Heightfield, Interpolation};
use crate::field::falloff::{WYVILL_MAX_SLOPE, wyvill};
use crate::field::{Interval, Rect};

/// An elevation and a weight at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The elevation `f`, metres.
    pub f: f32,
    /// The weight `α ≥ 0`.
    pub a: f32,
}

/// A disc primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Disc {
    /// Centre `c`.
    pub centre: Vec2,
    /// Radius of the weight's support.
    pub radius: f32,
    /// The elevation function, evaluated at `p − c`.
    pub elevation: ElevationFn,
}

impl Disc {
    /// `α = g(‖q‖ / r)` at offset `q` from the centre.
    #[inline]
    fn weight(&self, q: Vec2) -> f32 {
        disc_weight(q, self.radius * self.radius)
    }
}

/// A disc's weight `g(‖q‖ / r)` at offset `q` from its centre, `r2 = r²`, as
/// `(1 − ‖q‖² / r²)³₊`: no square root, and no branch.
#[inline(always)]
pub(super) fn disc_weight(q: Vec2, r2: f32) -> f32 {
    let s = (1.0 - q.length_squared() / r2).max(0.0);
    s * s * s
}

/// A curve primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    points: Vec<Vec3>,
    width: f32,
    profile: Profile,
    slope: f32,
}

impl Curve {
    /// A curve through `points` (at least 2) whose weight reaches `width` metres from it.
    pub fn new(points: Vec<Vec3>, width: f32, profile: Profile) -> Result<Curve, String> {
        if points.len() < 2 {
            return Err(format!(
                "`points` needs at least 2 points, found {}",
                points.len()
            ));
        }
        let slope = points
            .windows(2)
            .map(|w| {
                let run = (w[1] - w[0]).truncate().length();
                let rise = (w[1].z - w[0].z).abs();
                if rise == 0.0 { 0.0 } else { rise / run }
            })
            .fold(0.0, f32::max);
        if !slope.is_finite() {
            return Err(
                "`points`: two consecutive points at the same (x, y) with different z".into(),
            );
        }
        Ok(Curve {
            points,
            width,
            profile,
            slope: slope * 1.000_1,
        })
    }
}

/// A contour primitive.
#[derive(Clone, Debug, PartialEq)]
pub struct Contour {
    /// The closed polygon.
    pub polygon: Vec<Vec2>,
    /// The elevation `z` the profile is added to.
    pub elevation: f32,
    /// The profile of the signed distance to the contour.
    pub profile: Profile,
    /// How far outside the contour the weight reaches.
    pub falloff: f32,
}

/// An image primitive: a placed raster.
#[derive(Clone, Debug)]
pub struct Image {
    hf: Arc<Heightfield>,
    falloff: f32,
    lipschitz: f32,
    range: Interval,
}

impl Image {
    /// The raster `hf` (tree frame, every sample valid) with a weight falling to 0 over
    /// `falloff` metres inside its border.
    pub fn new(hf: Arc<Heightfield>, falloff: f32) -> Result<Image, String> {
        if hf.nodata_count() > 0 {
            return Err(format!(
                "the raster has {} nodata samples: an image primitive needs a full grid",
                hf.nodata_count()
            ));
        }
        let (lo, hi) = hf.z_range().ok_or("the raster has no sample")?;
        Ok(Image {
            lipschitz: hf.lipschitz(Interpolation::Bilinear) * 1.000_1,
            hf,
            falloff,
            range: Interval::new(lo, hi),
        })
    }
}

/// A primitive of an elevation tree.
#[derive(Clone, Debug)]
pub enum Primitive {
    /// See [`Disc`].
    Disc(Disc),
    /// See [`Curve`].
    Curve(Curve),
    /// See [`Contour`].
    Contour(Contour),
    /// See [`Image`].
    Image(Image),
}

impl Primitive {
    /// `(f(p), α(p))`.
    #[inline]
    pub fn eval(&self, p: Vec2, lod: &Lod) -> Sample {
        match self {
            Primitive::Disc(d) => {
                let q = p - d.centre;
                Sample {
                    f: d.elevation.value(q, lod),
                    a: d.weight(q),
                }
            }
            Primitive::Curve(c) => {
                let valley = c.profile.is_valley();
                let (mut f, mut dmin) = (
                    if valley {
                        f32::INFINITY
                    } else {
                        f32::NEG_INFINITY
                    },
                    f32::INFINITY,
                );
                for w in c.points.windows(2) {
                    let (d, t) = segment_distance(p, w[0].truncate(), w[1].truncate());
                    let fi = w[0].z + (w[1].z - w[0].z) * t + c.profile.value(d);
                    f = if valley { f.min(fi) } else { f.max(fi) };
                    dmin = dmin.min(d);
                }
                Sample {
                    f,
                    a: wyvill(dmin / c.width),
                }
            }
            Primitive::Contour(c) => {
                let s = polygon_signed_distance(&c.polygon, p);
                Sample {
                    f: c.elevation + c.profile.value(s),
                    a: wyvill(s.max(0.0) / c.falloff),
                }
            }
            Primitive::Image(im) => {
                let ext = im.hf.extent();
                let e = clearance(&ext, p);
                Sample {
                    f: im
                        .hf
                        .sample(p.clamp(ext.min, ext.max), Interpolation::Bilinear),
                    a: wyvill((im.falloff - e).max(0.0) / im.falloff),
                }
            }
        }
    }

    /// `(f(p), α(p))` where `α(p) > 0`, `None` elsewhere — the weight first, so a blend
    /// does not evaluate the elevation of a primitive that does not weigh at `p`.
    #[inline]
    pub fn eval_weighted(&self, p: Vec2, lod: &Lod) -> Option<Sample> {
        match self {
            Primitive::Disc(d) => {
                let q = p - d.centre;
                let a = d.weight(q);
                (a > 0.0).then(|| Sample {
                    f: d.elevation.value(q, lod),
                    a,
                })
            }
            _ => Some(self.eval(p, lod)).filter(|s| s.a > 0.0),
        }
    }

    /// The box outside which `α = 0`.
    pub fn support(&self) -> Rect {
        match self {
            Primitive::Disc(d) => Rect::new(d.centre, d.centre).dilate(d.radius),
            Primitive::Curve(c) => {
                let (lo, hi) = c
                    .points
                    .iter()
                    .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(p.truncate()), hi.max(p.truncate()))
                    });
                Rect::new(lo, hi).dilate(c.width)
            }
            Primitive::Contour(c) => {
                let (lo, hi) = c
                    .polygon
                    .iter()
                    .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(*p), hi.max(*p))
                    });
                Rect::new(lo, hi).dilate(c.falloff)
            }
            Primitive::Image(im) => im.hf.extent(),
        }
    }

    /// The global range of `f`.
    pub fn range(&self) -> Interval {
        match self {
            Primitive::Disc(d) => d.elevation.range(),
            Primitive::Curve(c) => {
                let z = c
                    .points
                    .iter()
                    .fold(Interval::EMPTY, |r, p| r.hull(Interval::point(p.z)));
                let pr = c.profile.range();
                Interval::new(z.lo + pr.lo, z.hi + pr.hi)
            }
            Primitive::Contour(c) => c.profile.range().shift(c.elevation),
            Primitive::Image(im) => im.range,
        }
    }

    /// A global Lipschitz bound of `f`.
    pub fn lipschitz_f(&self, lod: &Lod) -> f32 {
        match self {
            Primitive::Disc(d) => d.elevation.lipschitz(lod),
            Primitive::Curve(c) => c.slope + c.profile.lipschitz(),
            Primitive::Contour(c) => c.profile.lipschitz(),
            Primitive::Image(im) => im.lipschitz,
        }
    }

    /// A global Lipschitz bound of `α`: `max |g'| / R` (Génevaux et al. 2015, Appendix).
    pub fn lipschitz_a(&self) -> f32 {
        let r = match self {
            Primitive::Disc(d) => d.radius,
            Primitive::Curve(c) => c.width,
            Primitive::Contour(c) => c.falloff,
            Primitive::Image(im) => im.falloff,
        };
        WYVILL_MAX_SLOPE / r * 1.000_1
    }

    /// Ranges of `f` and `α` over `r`: the value at the centre ± the Lipschitz bound times
    /// the half-diagonal, clipped to the global ranges (`α = 0` off the support).
    pub fn ranges_over(&self, r: &Rect, lod: &Lod) -> (Interval, Interval) {
        let (c, hd) = rect_centre(r);
        let s = self.eval(c, lod);
        let g = self.range();
        let f = match self {
            Primitive::Disc(Disc {
                centre,
                elevation: ElevationFn::Fractal(m),
                ..
            }) => m.range_near(c - *centre, hd, lod),
            _ => {
                let eps = 1e-5 * (s.f.abs() + g.width());
                let reach = self.lipschitz_f(lod) * hd + eps;
                Interval::new(s.f - reach, s.f + reach)
            }
        };
        let f = Interval::new(f.lo.max(g.lo), f.hi.min(g.hi));
        let a = if self.support().overlaps(r) {
            let reach = self.lipschitz_a() * hd + 1e-6;
            Interval::new((s.a - reach).max(0.0), (s.a + reach).min(1.0))
        } else {
            Interval::ZERO
        };
        (f, a)
    }
}
