//! The compiled geology tree: each node's resistance, its gradient, and sound bounds over
//! boxes (a range and a Lipschitz bound) for the erosion node's interval answers.
//!
//! Values below the root are not clamped except by `Blend` (the clamped sum of
//! Paris et al. 2019 §4.2); the root clamps to `[0, 1]` ([`super::Geology`]). A fault
//! makes the resistance discontinuous on its domain's boundary (§4.4): a box across it
//! has no finite Lipschitz bound, and [`Rock::lipschitz_box`] says so with `+∞`.

use glam::Vec3;

use super::spec::{FaultSpec, ProfileSpec, RockSpec, StrataSpec, TaperSpec};
use crate::field::falloff::{wyvill_d, wyvill_interval, wyvill_slope};
use crate::field::{Aabb, Bound, Fbm, Field, Interval, NoiseSpec, Primitive, Warp};

/// Added turbulence `A·t(p)`.
#[derive(Clone, Debug)]
pub(super) struct Turb {
    fbm: Fbm,
    amplitude: f32,
}

impl Turb {
    fn new(spec: &NoiseSpec, seed: u32) -> Self {
        Turb {
            fbm: Fbm::new(spec, seed),
            amplitude: spec.amplitude.get(),
        }
    }
    fn value(&self, p: Vec3) -> f32 {
        self.amplitude * self.fbm.value(p)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (v, g) = self.fbm.value_grad(p);
        (self.amplitude * v, self.amplitude * g)
    }
    fn bound(&self, b: &Aabb) -> Bound {
        Bound::new(self.fbm.interval(b), self.fbm.lipschitz()).scale(self.amplitude)
    }
}

/// A 1D profile `g(d)` of the signed distance to a plane.
#[derive(Clone, Debug)]
pub(super) enum Profile {
    /// `v · wyvill(|d| / r)`.
    Band { inv_r: f32, value: f32 },
    /// Periodic layers: knots `starts[i]` (start of layer `i` in `[0, period)`), values,
    /// ramps of width `w` centred on every boundary.
    Layers {
        starts: Vec<f32>,
        values: Vec<f32>,
        period: f32,
        w: f32,
        slope: f32,
    },
    /// `base + A·t(d)` (the noise read along a line).
    Noise { base: f32, turb: Turb },
}

/// `3x² − 2x³` on `[0, 1]` and its derivative.
fn smoothstep(x: f32) -> (f32, f32) {
    let x = x.clamp(0.0, 1.0);
    (x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x))
}

impl Profile {
    fn new(spec: &ProfileSpec, seed: u32) -> Self {
        match spec {
            ProfileSpec::Band {
                half_width,
                resistance,
            } => Profile::Band {
                inv_r: 1.0 / half_width.get(),
                value: resistance.get(),
            },
            ProfileSpec::Noise { base, noise } => Profile::Noise {
                base: base.get(),
                turb: Turb::new(noise, seed),
            },
            ProfileSpec::Layers { layers, transition } => {
                let thinnest = layers
                    .iter()
                    .map(|l| l.thickness.get())
                    .fold(f32::INFINITY, f32::min);
                let w = transition.map_or(0.2 * thinnest, |t| t.get().min(thinnest));
                let mut starts = Vec::with_capacity(layers.len());
                let mut at = 0.0;
                for l in layers {
                    starts.push(at);
                    at += l.thickness.get();
                }
                let values: Vec<f32> = layers.iter().map(|l| l.resistance.get()).collect();
                let n = values.len();
                let jump = (0..n)
                    .map(|i| (values[(i + 1) % n] - values[i]).abs())
                    .fold(0.0, f32::max);
                Profile::Layers {
                    starts,
                    values,
                    period: at,
                    w,
                    // max of the smoothstep's slope, 3/2 per unit, over the ramp width.
                    slope: 1.5 * jump / w * 1.000_01,
                }
            }
        }
    }

    /// `(g(d), g'(d))`.
    fn value_d(&self, d: f32) -> (f32, f32) {
        match self {
            Profile::Band { inv_r, value } => {
                let (g, dg) = wyvill_d(d.abs() * inv_r);
                (value * g, value * dg * inv_r * d.signum())
            }
            Profile::Noise { base, turb } => {
                let (v, g) = turb.value_grad(Vec3::new(0.0, 0.0, d));
                (base + v, g.z)
            }
            Profile::Layers {
                starts,
                values,
                period,
                w,
                ..
            } => {
                let u = d.rem_euclid(*period);
                let n = values.len();
                // The layer holding u (starts[0] = 0 ≤ u).
                let i = starts.partition_point(|&s| s <= u) - 1;
                let end = starts.get(i + 1).copied().unwrap_or(*period);
                let h = 0.5 * w;
                let (a, b, x) = if u - starts[i] < h {
                    (values[(i + n - 1) % n], values[i], (u - starts[i] + h) / w)
                } else if end - u < h {
                    (values[i], values[(i + 1) % n], (u - end + h) / w)
                } else {
                    return (values[i], 0.0);
                };
                let (s, ds) = smoothstep(x);
                (a + (b - a) * s, (b - a) * ds / w)
            }
        }
    }

    /// The range of `g` and `max |g'|` over `d ∈ ds`.
    fn bound(&self, ds: Interval) -> Bound {
        match self {
            Profile::Band { inv_r, value } => {
                let abs = if ds.lo <= 0.0 && ds.hi >= 0.0 {
                    Interval::new(0.0, ds.lo.abs().max(ds.hi.abs()))
                } else {
                    Interval::new(ds.lo.abs(), ds.hi.abs())
                };
                let x = abs.scale(*inv_r);
                Bound::new(wyvill_interval(x), wyvill_slope(x) * inv_r).scale(*value)
            }
            Profile::Noise { base, turb } => turb
                .bound(&Aabb::new(
                    Vec3::new(0.0, 0.0, ds.lo),
                    Vec3::new(0.0, 0.0, ds.hi),
                ))
                .shift(*base),
            Profile::Layers {
                starts,
                values,
                period,
                w,
                slope,
            } => {
                let all = values
                    .iter()
                    .fold(Interval::EMPTY, |r, &v| r.hull(Interval::point(v)));
                if !(ds.width() < *period) {
                    return Bound::new(all, *slope);
                }
                // Monotone between plateaus: the extremes are at the ends or on a
                // plateau the range meets.
                let mut r = Interval::point(self.value_d(ds.lo).0)
                    .hull(Interval::point(self.value_d(ds.hi).0));
                let k0 = (ds.lo / period).floor();
                let h = 0.5 * w;
                for k in [k0 - 1.0, k0, k0 + 1.0] {
                    let base = k * period;
                    for (i, &s) in starts.iter().enumerate() {
                        let end = starts.get(i + 1).copied().unwrap_or(*period);
                        let (lo, hi) = (base + s + h, base + end - h);
                        if lo <= ds.hi && ds.lo <= hi {
                            r = r.hull(Interval::point(values[i]));
                        }
                    }
                }
                Bound::new(r, *slope)
            }
        }
    }
}

/// A compiled geology node.
#[derive(Clone, Debug)]
pub(super) enum Rock {
    Constant(f32),
    Strata {
        normal: Vec3,
        /// `normal · point`: `d(p) = normal · p − offset`.
        offset: f32,
        profile: Profile,
        turb: Option<Turb>,
    },
    Turbulence {
        base: f32,
        turb: Turb,
    },
    Local(Primitive),
    Blend(Vec<Rock>),
    Fold {
        warp: Warp,
        child: Box<Rock>,
    },
    Taper {
        /// Unit horizontal axis.
        axis: Vec3,
        from: f32,
        to: f32,
        factor: (f32, f32),
        z0: f32,
        child: Box<Rock>,
    },
    Fault {
        normal: Vec3,
        offset: f32,
        region: Option<Aabb>,
        slip: Vec3,
        child: Box<Rock>,
    },
}

/// Where a box lies with respect to a fault's domain.
enum Side {
    Inside,
    Outside,
    Across,
}

impl Rock {
    /// Compiles a spec; `seed` is the scene's global seed.
    pub(super) fn new(spec: &RockSpec, seed: u32) -> Rock {
        match spec {
            RockSpec::Constant(v) => Rock::Constant(v.get()),
            RockSpec::Strata(StrataSpec {
                point,
                normal,
                profile,
                turbulence,
            }) => {
                let normal = normal.unit();
                Rock::Strata {
                    normal,
                    offset: normal.dot(point.0),
                    profile: Profile::new(profile, seed),
                    turb: turbulence.as_ref().map(|t| Turb::new(t, seed)),
                }
            }
            RockSpec::Turbulence(t) => Rock::Turbulence {
                base: t.base.get(),
                turb: Turb::new(&t.noise, seed),
            },
            RockSpec::Local(p) => Rock::Local(Primitive::from_spec(p, seed)),
            RockSpec::Blend(cs) => Rock::Blend(cs.iter().map(|c| Rock::new(c, seed)).collect()),
            RockSpec::Fold(f) => Rock::Fold {
                warp: Warp::from_spec(
                    &f.turbulence,
                    f.region
                        .map(|r| (Aabb::new(r.min.0, r.max.0), r.falloff.get())),
                    seed,
                ),
                child: Box::new(Rock::new(&f.child, seed)),
            },
            RockSpec::Taper(TaperSpec {
                axis,
                from,
                to,
                factor,
                z0,
                child,
            }) => Rock::Taper {
                axis: axis.0.truncate().normalize().extend(0.0),
                from: from.get(),
                to: to.get(),
                factor: (factor.0.get(), factor.1.get()),
                z0: z0.get(),
                child: Box::new(Rock::new(child, seed)),
            },
            RockSpec::Fault(FaultSpec {
                point,
                normal,
                slip,
                region,
                child,
            }) => {
                let normal = normal.unit();
                Rock::Fault {
                    normal,
                    offset: normal.dot(point.0),
                    region: region.map(|b| Aabb::new(b.min.0, b.max.0)),
                    slip: slip.0,
                    child: Box::new(Rock::new(child, seed)),
                }
            }
        }
    }

    /// The taper's factor `s(p)` and `ds/d(axis·p)`.
    fn taper_factor(axis: Vec3, from: f32, to: f32, factor: (f32, f32), p: Vec3) -> (f32, f32) {
        let x = (axis.dot(p) - from) / (to - from);
        let slope = (factor.1 - factor.0) / (to - from);
        if (0.0..=1.0).contains(&x) {
            (factor.0 + (factor.1 - factor.0) * x, slope)
        } else {
            (if x < 0.0 { factor.0 } else { factor.1 }, 0.0)
        }
    }

    /// Whether `p` is strictly inside a fault's domain.
    fn in_fault(normal: Vec3, offset: f32, region: &Option<Aabb>, p: Vec3) -> bool {
        normal.dot(p) > offset && region.is_none_or(|r| r.contains(p))
    }

    fn fault_side(normal: Vec3, offset: f32, region: &Option<Aabb>, b: &Aabb) -> Side {
        let ds = plane_distances(normal, offset, b);
        let in_region = region.map_or(Side::Inside, |r| {
            if r.contains_box(b) {
                Side::Inside
            } else if r.overlaps(b) {
                Side::Across
            } else {
                Side::Outside
            }
        });
        match in_region {
            Side::Outside => Side::Outside,
            _ if ds.hi <= 0.0 => Side::Outside,
            Side::Inside if ds.lo > 0.0 => Side::Inside,
            _ => Side::Across,
        }
    }

    /// `ρ(p)` (unclamped below the blends).
    pub(super) fn value(&self, p: Vec3) -> f32 {
        match self {
            Rock::Constant(v) => *v,
            Rock::Strata {
                normal,
                offset,
                profile,
                turb,
            } => {
                let g = profile.value_d(normal.dot(p) - offset).0;
                g + turb.as_ref().map_or(0.0, |t| t.value(p))
            }
            Rock::Turbulence { base, turb } => base + turb.value(p),
            Rock::Local(prim) => prim.value(p),
            Rock::Blend(cs) => cs.iter().map(|c| c.value(p)).sum::<f32>().clamp(0.0, 1.0),
            Rock::Fold { warp, child } => child.value(warp.apply(p)),
            Rock::Taper {
                axis,
                from,
                to,
                factor,
                z0,
                child,
            } => {
                let (s, _) = Rock::taper_factor(*axis, *from, *to, *factor, p);
                child.value(Vec3::new(p.x, p.y, z0 + (p.z - z0) * s))
            }
            Rock::Fault {
                normal,
                offset,
                region,
                slip,
                child,
            } => {
                if Rock::in_fault(*normal, *offset, region, p) {
                    child.value(p - *slip)
                } else {
                    child.value(p)
                }
            }
        }
    }

    /// `(ρ(p), ∇ρ(p))`; at a clamp or on a fault's boundary, the gradient of one side.
    pub(super) fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        match self {
            Rock::Constant(v) => (*v, Vec3::ZERO),
            Rock::Strata {
                normal,
                offset,
                profile,
                turb,
            } => {
                let (g, dg) = profile.value_d(normal.dot(p) - offset);
                let (t, dt) = turb.as_ref().map_or((0.0, Vec3::ZERO), |t| t.value_grad(p));
                (g + t, *normal * dg + dt)
            }
            Rock::Turbulence { base, turb } => {
                let (t, g) = turb.value_grad(p);
                (base + t, g)
            }
            Rock::Local(prim) => prim.value_grad(p),
            Rock::Blend(cs) => {
                let (v, g) = cs.iter().fold((0.0, Vec3::ZERO), |(v, g), c| {
                    let (cv, cg) = c.value_grad(p);
                    (v + cv, g + cg)
                });
                if (0.0..=1.0).contains(&v) {
                    (v, g)
                } else {
                    (v.clamp(0.0, 1.0), Vec3::ZERO)
                }
            }
            Rock::Fold { warp, child } => {
                let (q, j) = warp.apply_jacobian(p);
                let (v, g) = child.value_grad(q);
                (v, j.transpose() * g)
            }
            Rock::Taper {
                axis,
                from,
                to,
                factor,
                z0,
                child,
            } => {
                let (s, ds) = Rock::taper_factor(*axis, *from, *to, *factor, p);
                let (v, g) = child.value_grad(Vec3::new(p.x, p.y, z0 + (p.z - z0) * s));
                // z' = z₀ + (z − z₀)·s(axis·p): ∇z' = (z − z₀)·s'·axis + s·ẑ.
                let dz = *axis * ((p.z - z0) * ds) + Vec3::Z * s;
                (v, Vec3::new(g.x, g.y, 0.0) + dz * g.z)
            }
            Rock::Fault {
                normal,
                offset,
                region,
                slip,
                child,
            } => {
                if Rock::in_fault(*normal, *offset, region, p) {
                    child.value_grad(p - *slip)
                } else {
                    child.value_grad(p)
                }
            }
        }
    }

    /// A range holding `ρ(p)` for every `p` in `b`, and a Lipschitz bound of `ρ` for
    /// pairs of points in `b`: `+∞` when `b` crosses a fault's boundary (`ρ` jumps there).
    pub(super) fn bound(&self, b: &Aabb) -> Bound {
        match self {
            Rock::Constant(v) => Bound::constant(*v),
            Rock::Strata {
                normal,
                offset,
                profile,
                turb,
            } => {
                let g = profile.bound(plane_distances(*normal, *offset, b));
                match turb {
                    Some(t) => g + t.bound(b),
                    None => g,
                }
            }
            Rock::Turbulence { base, turb } => turb.bound(b).shift(*base),
            Rock::Local(prim) => Bound::new(prim.interval(b), prim.lipschitz_box(b)),
            Rock::Blend(cs) => cs
                .iter()
                .fold(Bound::ZERO, |r, c| r + c.bound(b))
                .clamp(0.0, 1.0),
            Rock::Fold { warp, child } => child
                .bound(&b.dilate(warp.reach()))
                .warped(warp.lipschitz()),
            Rock::Taper {
                axis,
                from,
                to,
                factor,
                z0,
                child,
            } => {
                // ‖J‖₂ ≤ ‖J‖_F with J = I but for the z row (z − z₀)·s'·axis + s·ẑ.
                let s_max = factor.0.max(factor.1);
                let slope = (factor.1 - factor.0).abs() / (to - from).abs();
                let dz = (b.min.z - z0).abs().max((b.max.z - z0).abs());
                let norm = (2.0 + s_max * s_max + (dz * slope).powi(2)).sqrt() * 1.000_01;
                child
                    .bound(&taper_box(*axis, *from, *to, *factor, *z0, b))
                    .warped(norm)
            }
            Rock::Fault {
                normal,
                offset,
                region,
                slip,
                child,
            } => {
                let moved = || child.bound(&Aabb::new(b.min - *slip, b.max - *slip));
                match Rock::fault_side(*normal, *offset, region, b) {
                    Side::Inside => moved(),
                    Side::Outside => child.bound(b),
                    // Either side's values; a jump between them.
                    Side::Across => {
                        Bound::new(moved().range.hull(child.bound(b).range), f32::INFINITY)
                    }
                }
            }
        }
    }
}

/// The range of `normal · p − offset` over `b`, widened by an ulp-scale margin.
fn plane_distances(normal: Vec3, offset: f32, b: &Aabb) -> Interval {
    let c = b.center();
    let r = (b.size() * 0.5).dot(normal.abs());
    let d = normal.dot(c) - offset;
    let eps = 1e-6 * (c.abs().max_element() + offset.abs() + r);
    Interval::new(d - r - eps, d + r + eps)
}

/// The box where a taper reads its child for points of `b`.
fn taper_box(axis: Vec3, from: f32, to: f32, factor: (f32, f32), z0: f32, b: &Aabb) -> Aabb {
    // s is monotone along the axis: its range over b's footprint is at the extreme corners.
    let us = b.corners().iter().fold(Interval::EMPTY, |r, c| {
        r.hull(Interval::point(axis.dot(*c)))
    });
    let s = |u: f32| {
        let x = ((u - from) / (to - from)).clamp(0.0, 1.0);
        factor.0 + (factor.1 - factor.0) * x
    };
    let ss = Interval::new(s(us.lo), s(us.hi));
    let (za, zb) = (b.min.z - z0, b.max.z - z0);
    let prods = [za * ss.lo, za * ss.hi, zb * ss.lo, zb * ss.hi];
    let lo = prods.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = prods.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let eps = 1e-6 * (z0.abs() + lo.abs().max(hi.abs())) + 1e-6;
    Aabb::new(
        Vec3::new(b.min.x, b.min.y, z0 + lo - eps),
        Vec3::new(b.max.x, b.max.y, z0 + hi + eps),
    )
}
