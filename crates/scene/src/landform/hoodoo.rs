//! Hoodoos and goblins (Paris et al. 2019 §6.3). Where they grow is a probability from
//! the terrain analysis — medium slope (talus, cliff feet) and low drainage area, inside
//! an optional mask polygon — sampled with Poisson-disk spacing; each sample is the axiom
//! of the open grammar of Fig. 20:
//!
//! ```text
//! A(p, s) → B(p, s)
//! B(p, s) → b(p, s) B(p + s·z, λs)     probability p_B(ρ)
//!         → b(p, s) C(p + s·z, λs)     1 − p_B(ρ)
//! C(p, s) → c(p, s) B(p + s·z, λs)     ½ p_C(ρ)
//!         → c(p, s)                    ½ p_C(ρ)
//!         → d(p, s)                    1 − p_C(ρ)
//! ```
//!
//! with terminals `b` a body (an upright ellipsoid: stacked bodies overlap into a column
//! with the waists and bulges of a totem), `c` a cone (a spire) and `d` a caprock (a
//! flattened ellipsoid wider than the column it crowns), stacked up the vertical through
//! the axiom. The rock's resistance ρ at each symbol drives the probabilities (harder
//! rock: taller stacks, more caps) and the sizes (softer rock: slimmer bodies); each
//! symbol's cross-section is an ellipse of random elongation. At `max_depth` symbols the
//! grammar ends on a terminal. The primitives carry a noise displacement of a tenth of
//! the first symbol's height, so the columns read as weathered rock, not turned solids.

use glam::{Vec2, Vec3};

use super::{Ground, LandformError, Poisson, smoothstep, solid};
use crate::analysis::flow::{drainage_area, fill_depressions};
use crate::analysis::relief::slope;
use crate::field::noise::Octaves;
use crate::field::skeleton::Size3;
use crate::field::{NoiseSpec, SkeletonSpec};
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::landform::HoodooSpec;
use crate::value::{NonNegative, P2, P3, Positive};

/// A caprock's thickness, as a fraction of its symbol's height: caps are flat slabs.
pub const CAP: f32 = 0.4;

/// A terminal symbol of the grammar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Terminal {
    /// A body of the column (`b`).
    Body,
    /// A spire (`c`).
    Cone,
    /// A caprock (`d`).
    Cap,
}

/// One hoodoo: its axiom and the terminals stacked from it.
#[derive(Clone, Debug)]
pub struct Hoodoo {
    /// Where the axiom stands (its foot, a little into the ground).
    pub axiom: Vec3,
    /// The terminals, bottom up: kind, base point, height, elongation of the cross-section
    /// (the ratio of its x and y radii, in `[0.75, 1.33]`), resistance.
    pub symbols: Vec<(Terminal, Vec3, f32, f32, f32)>,
}

impl Hoodoo {
    /// Height of the top of the last symbol above the axiom (a caprock is [`CAP`] of its
    /// symbol's height thick).
    pub fn height(&self) -> f32 {
        self.symbols.last().map_or(0.0, |&(t, p, s, _, _)| {
            let top = if t == Terminal::Cap { CAP * s } else { s };
            p.z + top - self.axiom.z
        })
    }
}

fn inside(poly: &[P2], p: Vec2) -> bool {
    let mut odd = false;
    for (k, a) in poly.iter().enumerate() {
        let b = poly[(k + 1) % poly.len()];
        let (a, b) = (a.0, b.0);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            odd = !odd;
        }
    }
    odd
}

impl HoodooSpec {
    /// The probability of growth at each sample of the ground's top grid.
    pub fn probability(&self, ground: &Ground) -> Vec<f32> {
        let top = &ground.top;
        let s = slope(top);
        let area = drainage_area(&fill_depressions(top));
        let (lo, hi) = (self.slope.0.0, self.slope.1.0);
        let margin = 0.25 * (hi - lo).abs().max(1e-3);
        (0..s.len())
            .map(|k| {
                if top.samples()[k].is_nan() {
                    return 0.0;
                }
                let in_mask = self
                    .mask
                    .as_ref()
                    .is_none_or(|m| inside(m, ground.sample_point(k).truncate()));
                let band =
                    smoothstep(lo - margin, lo, s[k]) * (1.0 - smoothstep(hi, hi + margin, s[k]));
                let dry = (1.0 - area[k] / self.max_area.0).max(0.0);
                if in_mask { band * dry } else { 0.0 }
            })
            .collect()
    }

    /// The hoodoos: axioms by Poisson sampling of the probability, grown by the grammar.
    pub fn hoodoos(&self, ground: &Ground) -> Result<Vec<Hoodoo>, LandformError> {
        if self.max_depth == 0 {
            return Err(LandformError::Invalid(
                "hoodoo `max_depth` must be at least 1".into(),
            ));
        }
        let prob = self.probability(ground);
        let mut rng = Rng::new(ground.seed);
        let mut poisson = Poisson::new(self.spacing.0);
        let mut out = Vec::new();
        let cell = ground.top.cell();
        for (k, &pk) in prob.iter().enumerate() {
            let (u, jx, jy) = (rng.unit(), rng.unit() - 0.5, rng.unit() - 0.5);
            if pk <= 0.0 || u >= pk {
                continue;
            }
            let xy = ground.sample_point(k).truncate() + Vec2::new(jx, jy) * cell;
            let h = ground.height(xy);
            if !h.is_finite() || !poisson.take(xy.extend(0.0)) {
                continue;
            }
            let axiom = xy.extend(h - 0.25 * self.size.0);
            out.push(self.grow(ground, axiom, &mut rng));
        }
        Ok(out)
    }

    /// Derives one hoodoo from its axiom.
    fn grow(&self, ground: &Ground, axiom: Vec3, rng: &mut Rng) -> Hoodoo {
        #[derive(Clone, Copy)]
        enum Symbol {
            B,
            C,
        }
        let mut symbols = Vec::new();
        let (mut p, mut s) = (axiom, self.size.0 * (0.8 + 0.4 * rng.unit()));
        // A → B
        let mut next = Some(Symbol::B);
        while let Some(sym) = next {
            let rho = (ground.resistance)(p + 0.5 * s * Vec3::Z);
            let last = symbols.len() + 1 >= self.max_depth as usize;
            let u = rng.unit();
            let elongation = 0.75 + 0.58 * rng.unit();
            let (terminal, then) = match sym {
                Symbol::B => {
                    let p_b = 0.3 + 0.6 * rho;
                    let then = if !last && u < p_b {
                        Symbol::B
                    } else {
                        Symbol::C
                    };
                    (Terminal::Body, Some(then))
                }
                Symbol::C => {
                    let p_c = 1.0 - 0.5 * rho;
                    if last {
                        (
                            if u < 0.5 * p_c {
                                Terminal::Cone
                            } else {
                                Terminal::Cap
                            },
                            None,
                        )
                    } else if u < 0.5 * p_c {
                        (Terminal::Cone, Some(Symbol::B))
                    } else if u < p_c {
                        (Terminal::Cone, None)
                    } else {
                        (Terminal::Cap, None)
                    }
                }
            };
            // A body at the depth bound leaves no room for its C: end on the body.
            let then = if last { None } else { then };
            symbols.push((terminal, p, s, elongation, rho));
            p += s * Vec3::Z;
            s *= self.lambda.0.max(0.05);
            next = then;
        }
        Hoodoo { axiom, symbols }
    }

    /// The primitives of the hoodoos: ellipsoids and cones, solid to their faces; bodies and
    /// caps carry a weathering noise of a fifth of their radius (too little to cut a
    /// column through), spires none (it would shave their tips).
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        let falloff = 0.1 * self.size.0;
        let weathering = |width: f32| NoiseSpec {
            amplitude: NonNegative(0.2 * width),
            wavelength: Positive(0.5 * self.size.0),
            octaves: Octaves::new(2).unwrap_or_default(),
            seed_offset: 0,
        };
        Ok(self
            .hoodoos(ground)?
            .iter()
            .flat_map(|h| h.symbols.iter())
            .map(|&(t, p, s, elongation, rho)| {
                let width = s * (0.22 + 0.16 * rho);
                let (rx, ry) = (width * elongation.sqrt(), width / elongation.sqrt());
                let (shape, noise) = match t {
                    // Taller than the symbol, so a body overlaps the next one by a fifth.
                    Terminal::Body => (
                        SkeletonSpec::Ellipsoid {
                            center: P3(p + 0.5 * s * Vec3::Z),
                            radii: Size3(Vec3::new(rx, ry, 0.6 * s)),
                        },
                        Some(weathering(width)),
                    ),
                    Terminal::Cap => (
                        SkeletonSpec::Ellipsoid {
                            center: P3(p + 0.5 * CAP * s * Vec3::Z),
                            radii: Size3(Vec3::new(2.0 * rx, 2.0 * ry, 0.6 * CAP * s)),
                        },
                        Some(weathering(width)),
                    ),
                    Terminal::Cone => (
                        SkeletonSpec::Cone {
                            base: P3(p - 0.1 * s * Vec3::Z),
                            apex: P3(p + s * Vec3::Z),
                            radius: Positive(1.1 * width),
                        },
                        None,
                    ),
                };
                solid(shape, falloff, noise)
            })
            .collect())
    }
}
