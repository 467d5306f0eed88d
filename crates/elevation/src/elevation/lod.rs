//! Continuous level of detail (Génevaux et al. 2015 §6).
//!
//! A query carries a resolution `ρ` (metres: the pixel's or the mesh cell's footprint). A
//! detail of size `s` (a noise octave's wavelength, an `Add` node's `size`) is weighted by
//! the filter `b(κ)` of `κ = s / ρ`, the detail's size in pixels: 0 for `κ ≤ k⁻`, 1 for
//! `κ ≥ k⁺`, and `1 − (1 − t²)³` with `t = (κ − k⁻)/(k⁺ − k⁻)` between. The paper prints
//! `(1 − t²)³` for the middle piece, which jumps from 0 to 1 at `k⁻`; its complement is
//! the smooth (C¹) increasing filter the text describes. `ρ = 0` is the level ∞: every
//! filter is exactly 1 and the evaluation is the full one.

use crate::field::falloff::wyvill;

/// Below `κ = k⁻` a detail is cut: it is smaller than one pixel.
pub const K_MINUS: f32 = 1.0;
/// Above `κ = k⁺` a detail is kept whole.
pub const K_PLUS: f32 = 2.0;

/// The level of detail of a query: the resolution `ρ` in metres (0: full detail).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lod {
    resolution: f32,
}

impl Lod {
    /// Full detail (level ∞).
    pub const FULL: Lod = Lod { resolution: 0.0 };

    /// Details smaller than about `resolution` metres are cut (negative or NaN: full).
    pub fn new(resolution: f32) -> Lod {
        Lod {
            resolution: if resolution > 0.0 { resolution } else { 0.0 },
        }
    }

    /// The resolution `ρ` (0 at full detail).
    pub fn resolution(&self) -> f32 {
        self.resolution
    }

    /// The weight `b(s / ρ) ∈ [0, 1]` of a detail of size `size` metres.
    #[inline]
    pub fn filter(&self, size: f32) -> f32 {
        if self.resolution == 0.0 {
            return 1.0;
        }
        let kappa = size / self.resolution;
        if kappa >= K_PLUS {
            1.0
        } else if kappa <= K_MINUS {
            0.0
        } else {
            1.0 - wyvill((kappa - K_MINUS) / (K_PLUS - K_MINUS))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filter_is_continuous_and_monotone() {
        let lod = Lod::new(1.0);
        let mut last = 0.0;
        for i in 0..=3000 {
            let b = lod.filter(i as f32 * 1e-3);
            assert!(b >= last && (b - last) < 5e-3, "at {i}: {last} -> {b}");
            last = b;
        }
        assert_eq!(lod.filter(0.5), 0.0);
        assert_eq!(lod.filter(2.5), 1.0);
        assert_eq!(Lod::FULL.filter(1e-9), 1.0);
    }
}
