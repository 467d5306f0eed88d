//! Elevation functions of skeletal primitives: constant, fBm, ridged and hybrid
//! multifractals (Génevaux et al. 2015 §4.1, after Musgrave et al. 1989), built on the
//! project's seeded simplex noise (`field::noise`: the same lattice, seeds and octave
//! shifts as [`Fbm`]), with a range, a Lipschitz bound and continuous LoD.
//!
//! Each function sums octaves `k < o` of the noise `n_k` (wavelength `λ / 2^k`,
//! `|∇n_k| ≤ λ_η 2^k / λ`, `λ_η` = [`SIMPLEX_LIPSCHITZ`]) weighted `a_k = ½^k`:
//!
//! * **fBm**: `c_k = a_k n_k`;
//! * **ridged**: `s_k = (1 − |n_k|)²`, `w_0 = 1`, `w_k = clamp(g s̃_{k−1}, 0, 1)`,
//!   `s̃_k = w_k s_k`, `c_k = a_k s̃_k` (the previous octave's ridge gates the next, so
//!   detail gathers on the crests). Elevation trees take the gate gain `g = 1`;
//!   Musgrave's `g = 2` ([`Multifractal::musgrave`], the procedural generators) makes the
//!   bound grow as `k 2^k` instead of `2^k`;
//! * **hybrid**: `s_k = a_k (n_k + 0.7)`, `c_0 = s_0`, `w_1 = clamp(s_0, 0, 1)`,
//!   `c_k = w_k s_k`, `w_{k+1} = clamp(w_k s_k, 0, 1)` (smooth valleys, rough peaks).
//!
//! Every `c_k` lies in a known range `[l_k, u_k]` and has a Lipschitz bound `L_k` by the
//! product and chain rules (`|s_k| ≤ 1`, clamping is 1-Lipschitz): ridged
//! `L(s_k) = 2 λ_η 2^k/λ`, `L(s̃_k) ≤ L(s_k) + L(s̃_{k−1})`; hybrid
//! `L(c_k) ≤ L(w_k) max|s_k| + L(s_k)`, `L(w_{k+1}) ≤ L(c_k)`. Continuous LoD
//! (Génevaux et al. 2015 §6) replaces octave `k` by `b_k c_k + (1 − b_k) m_k`, `m_k` the
//! middle of its range, so the elevation keeps its range as octaves fade out. The raw sum
//! is mapped onto `[base, base + amplitude]`, so the bound is
//! `λ = amplitude / Σ(u_k − l_k) · Σ b_k L_k` — Génevaux et al. 2015 §7.3.1's
//! `Σ a_i λ_η / s_i`, filtered by the level of detail.

use glam::Vec2;

use super::lod::Lod;
use crate::field::Interval;
pub use crate::field::lanes::Lanes;
use crate::field::noise::{Fbm, GAIN, LACUNARITY, MAX_OCTAVES, NoiseLanes, SIMPLEX_LIPSCHITZ};

/// The hybrid multifractal's offset (Musgrave's 0.7).
const HYBRID_OFFSET: f32 = 0.7;

/// Which octave sum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Fractional Brownian motion: rolling hills.
    Fbm,
    /// Ridged multifractal: sharp crests, mountains.
    Ridged,
    /// Hybrid multifractal: smooth lowlands, rough heights.
    Hybrid,
}

/// An elevation function `h: R² → [base, base + amplitude]`.
#[derive(Clone, Debug, PartialEq)]
pub enum ElevationFn {
    /// `h = c`: a plain or a plateau.
    Constant(f32),
    /// A multifractal octave sum.
    Fractal(Multifractal),
}

/// A multifractal of the kinds of [`Kind`].
#[derive(Clone, Debug, PartialEq)]
pub struct Multifractal {
    kind: Kind,
    noise: Fbm,
    /// The ridged gate's gain `g`: `w_k = clamp(g s̃_{k−1}, 0, 1)`.
    gate: f32,
    base: f32,
    /// `amplitude / Σ(u_k − l_k)`.
    scale: f32,
    /// Per octave: `[l_k, u_k]`, `L_k`, wavelength.
    octaves: Vec<Octave>,
    /// `Σ l_k`.
    lo: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Octave {
    amp: f32,
    range: Interval,
    lipschitz: f32,
    wavelength: f32,
}

impl Multifractal {
    /// A `kind` multifractal from `base` to `base + amplitude` (metres), first-octave
    /// wavelength `wavelength` (> 0), `octaves` in `1..=12` (clamped), noise `seed`: the
    /// elevation trees' octave sums (amplitudes `½^k`, ridged gate gain 1).
    pub fn new(
        kind: Kind,
        base: f32,
        amplitude: f32,
        wavelength: f32,
        octaves: u32,
        seed: u32,
    ) -> Multifractal {
        Multifractal::with(
            kind,
            (base, amplitude),
            wavelength,
            octaves,
            seed,
            (1.0, GAIN),
        )
    }

    /// Musgrave's own parameters (Musgrave 2003, ch. 16), on `[0, 1]`: the ridged gate's
    /// gain 2 (detail gathers on the crests more sharply) and the hybrid's `H = 0.25`
    /// (octave amplitudes `2^{−k/4}`: rougher heights). The procedural generators use
    /// these; an elevation tree keeps [`Multifractal::new`]'s tighter bounds.
    pub fn musgrave(kind: Kind, wavelength: f32, octaves: u32, seed: u32) -> Multifractal {
        let persistence = match kind {
            Kind::Hybrid => LACUNARITY.powf(-0.25),
            Kind::Fbm | Kind::Ridged => GAIN,
        };
        let gate = match kind {
            Kind::Ridged => 2.0,
            Kind::Fbm | Kind::Hybrid => 1.0,
        };
        Multifractal::with(
            kind,
            (0.0, 1.0),
            wavelength,
            octaves,
            seed,
            (gate, persistence),
        )
    }

    /// The octave table for `(base, amplitude)`, `(gate, persistence)`: each octave's
    /// range and slope by the product and chain rules (module docs; a gate of gain `g`
    /// multiplies the chained slope by `g`).
    fn with(
        kind: Kind,
        (base, amplitude): (f32, f32),
        wavelength: f32,
        octaves: u32,
        seed: u32,
        (gate, persistence): (f32, f32),
    ) -> Multifractal {
        let noise = Fbm::with(seed, wavelength, octaves.clamp(1, MAX_OCTAVES));
        let mut table = Vec::new();
        let (mut a, mut freq) = (1.0f32, 1.0 / wavelength);
        // ridged: L(s̃_{k−1}); hybrid: L(w_k)
        let mut chain = 0.0f32;
        for k in 0..noise.octaves() {
            let ln = SIMPLEX_LIPSCHITZ * freq;
            let (range, lip) = match kind {
                Kind::Fbm => (Interval::new(-a, a), a * ln),
                Kind::Ridged => {
                    let l = 2.0 * ln + gate * chain;
                    chain = l;
                    (Interval::new(0.0, a), a * l)
                }
                Kind::Hybrid => {
                    let smax = a * (1.0 + HYBRID_OFFSET);
                    let ls = a * ln;
                    if k == 0 {
                        chain = ls;
                        (Interval::new(a * (HYBRID_OFFSET - 1.0), smax), ls)
                    } else {
                        let l = chain * smax + ls;
                        chain = l;
                        (Interval::new(a * (HYBRID_OFFSET - 1.0), smax), l)
                    }
                }
            };
            table.push(Octave {
                amp: a,
                range,
                lipschitz: lip * 1.000_1,
                wavelength: 1.0 / freq,
            });
            a *= persistence;
            freq *= LACUNARITY;
        }
        let width: f32 = table.iter().map(|o| o.range.width()).sum();
        Multifractal {
            kind,
            noise,
            gate,
            base,
            scale: amplitude / width,
            lo: table.iter().map(|o| o.range.lo).sum(),
            octaves: table,
        }
    }

    /// How many octaves `lod` keeps: those before the first whose filter is 0 (the
    /// wavelengths fall with `k`, so every later filter is 0 too). A cut octave `k` adds
    /// the middle `m_k` of its range, and its noise is not evaluated.
    #[inline(always)]
    fn live(&self, lod: &Lod) -> usize {
        self.octaves
            .iter()
            .position(|o| lod.filter(o.wavelength) == 0.0)
            .unwrap_or(self.octaves.len())
    }

    /// `Σ m_k` over the octaves that `lod` cuts, from octave `live` on.
    #[inline(always)]
    fn cut_mids(&self, live: usize) -> f32 {
        self.octaves[live..].iter().map(|o| o.range.mid()).sum()
    }

    /// Visits each octave's contribution `c_k(p)` with its table entry, for the first
    /// `live` octaves.
    #[inline(always)]
    fn octaves(&self, p: Vec2, live: usize, mut visit: impl FnMut(f32, &Octave)) {
        // The octaves' noises first, four at a time (they are independent), then their
        // combination, in order.
        let mut noise = [0.0f32; MAX_OCTAVES as usize];
        let mut q = (p * self.noise.inv_wavelength()).extend(0.0);
        for (k0, chunk) in noise[..live.next_multiple_of(4)]
            .chunks_exact_mut(4)
            .enumerate()
        {
            chunk.copy_from_slice(&self.noise.octaves4(4 * k0 as u32, q).to_array());
            q *= LACUNARITY.powi(4);
        }
        let mut w = 1.0f32;
        for (k, (o, &n)) in self.octaves[..live].iter().zip(&noise).enumerate() {
            let a = o.amp;
            let c = match self.kind {
                Kind::Fbm => a * n,
                Kind::Ridged => {
                    let s = (1.0 - n.abs()).powi(2) * w;
                    w = (self.gate * s).clamp(0.0, 1.0);
                    a * s
                }
                Kind::Hybrid => {
                    let s = a * (n + HYBRID_OFFSET);
                    if k == 0 {
                        w = s.clamp(0.0, 1.0);
                        s
                    } else {
                        let c = w * s;
                        w = c.clamp(0.0, 1.0);
                        c
                    }
                }
            };
            visit(c, o);
        }
    }

    /// `h(p)` at level of detail `lod`.
    #[inline]
    pub fn value(&self, p: Vec2, lod: &Lod) -> f32 {
        let live = self.live(lod);
        let mut sum = 0.0;
        self.octaves(p, live, |c, o| {
            let b = lod.filter(o.wavelength);
            sum += if b == 1.0 {
                c
            } else {
                b * c + (1.0 - b) * o.range.mid()
            };
        });
        if live < self.octaves.len() {
            sum += self.cut_mids(live);
        }
        self.base + self.scale * (sum - self.lo)
    }

    /// `h` at `L::N` points, `(x, y)[l]` on lane `l`: each lane is [`Multifractal::value`]
    /// bit for bit — the same operations in the same order on the lanes, the noise one
    /// octave of the points at a time ([`Fbm::octave_lanes`]) instead of four octaves of
    /// one point, so no lane is idle when there are fewer than four octaves.
    #[inline(always)]
    pub(super) fn values_lanes<L: NoiseLanes>(&self, x: L, y: L, lod: &Lod) -> L {
        let live = self.live(lod);
        let inv = L::splat(self.noise.inv_wavelength());
        let mut q = [x * inv, y * inv, L::ZERO];
        let (mut w, mut sum) = (L::ONE, L::ZERO);
        for (k, o) in self.octaves[..live].iter().enumerate() {
            if k > 0 && k % 4 == 0 {
                let s = L::splat(LACUNARITY.powi(4));
                q = [q[0] * s, q[1] * s, q[2] * s];
            }
            let n = self.noise.octave_lanes(k as u32, q);
            let a = L::splat(o.amp);
            let c = match self.kind {
                Kind::Fbm => a * n,
                Kind::Ridged => {
                    let r = L::ONE - n.abs();
                    let s = r * r * w;
                    w = clamp01(L::splat(self.gate) * s);
                    a * s
                }
                Kind::Hybrid => {
                    let s = a * (n + L::splat(HYBRID_OFFSET));
                    if k == 0 {
                        w = clamp01(s);
                        s
                    } else {
                        let c = w * s;
                        w = clamp01(c);
                        c
                    }
                }
            };
            let b = lod.filter(o.wavelength);
            sum += if b == 1.0 {
                c
            } else {
                L::splat(b) * c + L::splat((1.0 - b) * o.range.mid())
            };
        }
        if live < self.octaves.len() {
            sum += L::splat(self.cut_mids(live));
        }
        L::splat(self.base) + L::splat(self.scale) * (sum - L::splat(self.lo))
    }

    /// A range of `h` over the disc of radius `reach` around `p`: per octave,
    /// `c_k(p) ± L_k · reach` clipped to `[l_k, u_k]`, summed. The coarse octaves are
    /// bounded by their slope, the fine ones by their small amplitude.
    pub fn range_near(&self, p: Vec2, reach: f32, lod: &Lod) -> Interval {
        let live = self.live(lod);
        let (mut lo, mut hi) = (0.0f32, 0.0f32);
        self.octaves(p, live, |c, o| {
            let b = lod.filter(o.wavelength);
            let r = o.lipschitz * reach;
            let (l, u) = ((c - r).max(o.range.lo), (c + r).min(o.range.hi));
            let m = (1.0 - b) * o.range.mid();
            lo += b * l + m;
            hi += b * u + m;
        });
        if live < self.octaves.len() {
            let m = self.cut_mids(live);
            (lo, hi) = (lo + m, hi + m);
        }
        let eps = 1e-5 * (self.base.abs() + self.scale * (hi - lo) + 1.0);
        Interval::new(
            self.base + self.scale * (lo - self.lo) - eps,
            self.base + self.scale * (hi - self.lo) + eps,
        )
    }

    /// A Lipschitz bound of `h` at level of detail `lod`.
    pub fn lipschitz(&self, lod: &Lod) -> f32 {
        self.scale
            * self
                .octaves
                .iter()
                .map(|o| lod.filter(o.wavelength) * o.lipschitz)
                .sum::<f32>()
    }

    /// The range `[base, base + amplitude]`.
    pub fn range(&self) -> Interval {
        let w: f32 = self.octaves.iter().map(|o| o.range.width()).sum();
        Interval::new(self.base, self.base + self.scale * w)
    }
}

/// `f32::clamp(v, 0, 1)` on each lane, NaN and the sign of a zero included.
#[inline(always)]
fn clamp01<L: Lanes>(v: L) -> L {
    let (zero, one) = (L::ZERO, L::ONE);
    L::select(v.cmplt(zero), zero, L::select(v.cmpgt(one), one, v))
}

impl ElevationFn {
    /// `h(p)`.
    #[inline]
    pub fn value(&self, p: Vec2, lod: &Lod) -> f32 {
        match self {
            ElevationFn::Constant(c) => *c,
            ElevationFn::Fractal(m) => m.value(p, lod),
        }
    }

    /// A global Lipschitz bound.
    pub fn lipschitz(&self, lod: &Lod) -> f32 {
        match self {
            ElevationFn::Constant(_) => 0.0,
            ElevationFn::Fractal(m) => m.lipschitz(lod),
        }
    }

    /// The global range.
    pub fn range(&self) -> Interval {
        match self {
            ElevationFn::Constant(c) => Interval::point(*c),
            ElevationFn::Fractal(m) => m.range(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both parameter sets keep their values in their range and their slopes under their
    /// bound, sampled along lines across many wavelengths.
    #[test]
    fn elevation_and_musgrave_sums_stay_within_their_bounds() {
        let kinds = [Kind::Fbm, Kind::Ridged, Kind::Hybrid];
        let sums = kinds.iter().flat_map(|&k| {
            [
                Multifractal::new(k, 10.0, 90.0, 300.0, 6, 3),
                Multifractal::musgrave(k, 300.0, 6, 3),
            ]
        });
        for m in sums {
            let (range, lip) = (m.range(), m.lipschitz(&Lod::FULL));
            let mut steepest = 0.0f32;
            for line in 0..40 {
                let (o, d) = (Vec2::new(line as f32 * 37.0, 11.0), Vec2::new(0.6, 0.8));
                let mut prev = m.value(o, &Lod::FULL);
                for i in 1..4000 {
                    let v = m.value(o + d * (i as f32 * 0.5), &Lod::FULL);
                    assert!(
                        range.dilate(1e-3).contains(v),
                        "{:?}: {v} ∉ {range:?}",
                        m.kind
                    );
                    steepest = steepest.max((v - prev).abs() / 0.5);
                    prev = v;
                }
            }
            assert!(steepest <= lip, "{:?}: slope {steepest} > {lip}", m.kind);
        }
    }
}
