//! An [`Inset`]: changes to a DEM over a rectangle on a finer lattice, with the traces of
//! what made them, such as the eroded amplification of the scene's erosion module.

use glam::Vec2;

use super::{DemError, Heightfield};

/// What an amplification leaves on its lattice besides the elevation changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Trace {
    /// Drainage area, m².
    Area,
    /// Depth of the ground below the DEM, metres: how deep the water cut.
    Incision,
    /// Thickness of the talus lying on the sample, metres.
    Talus,
    /// Thickness of the sediment water left on the sample, metres.
    Deposit,
}

impl Trace {
    /// Every trace, in a fixed order.
    pub const ALL: [Trace; 4] = [Trace::Area, Trace::Incision, Trace::Talus, Trace::Deposit];
}

/// Elevation changes `δ` on a fine lattice (zero on its border) and the traces of the
/// process that made them, one value per sample of the lattice.
#[derive(Clone, Debug, PartialEq)]
pub struct Inset {
    delta: Heightfield,
    traces: [Vec<f32>; 4],
}

impl Inset {
    /// An inset of changes `delta` with `traces` in [`Trace::ALL`]'s order, each with one
    /// value per sample.
    pub fn new(delta: Heightfield, traces: [Vec<f32>; 4]) -> Result<Inset, DemError> {
        let n = delta.samples().len();
        if let Some(t) = traces.iter().position(|t| t.len() != n) {
            return Err(DemError::Invalid {
                what: format!(
                    "the inset's {:?} trace has {} values for {n} samples",
                    Trace::ALL[t],
                    traces[t].len()
                ),
            });
        }
        Ok(Inset { delta, traces })
    }

    /// The changes `δ`.
    pub fn delta(&self) -> &Heightfield {
        &self.delta
    }

    /// The values of trace `t`, one per sample.
    pub fn trace(&self, t: Trace) -> &[f32] {
        &self.traces[t as usize]
    }

    /// Trace `t` at `xy`, bilinear between samples; 0 off the lattice.
    pub fn trace_at(&self, t: Trace, xy: Vec2) -> f32 {
        let d = &self.delta;
        let u = (xy - d.origin()) / d.cell();
        if !(u.x >= 0.0 && u.y >= 0.0) {
            return 0.0;
        }
        let (i, j) = (u.x as usize, u.y as usize);
        if i + 1 >= d.nx() || j + 1 >= d.ny() {
            return 0.0;
        }
        let v = self.trace(t);
        let (a, b) = (u.x - i as f32, u.y - j as f32);
        let k = i + d.nx() * j;
        let lo = v[k] + (v[k + 1] - v[k]) * a;
        let hi = v[k + d.nx()] + (v[k + d.nx() + 1] - v[k + d.nx()]) * a;
        lo + (hi - lo) * b
    }
}
