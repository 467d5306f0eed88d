//! Erosion of heightfields: uplift and stream-power fluvial incision solved implicitly in
//! O(n) (Braun and Willett 2013), optional hillslope diffusion, and thermal erosion down to
//! a talus angle (Musgrave, Kolb and Mace 1989).
//!
//! * [`stream_power`]: one step of uplift and `∂h/∂t = U − K A^m S^n` along the flow
//!   graph's stack ([`crate::analysis::flow::FlowGraph`]);
//! * [`diffusion`]: `∂h/∂t = D ∇²h`, alternating-direction implicit;
//! * [`thermal`]: talus-angle relaxation;
//! * [`transport`]: sediment carried down the drainage and deposited;
//! * [`amplify`]: the eroded amplification of a DEM, constrained to keep it;
//! * [`ErosionStage`]: the tree-file and command-line form, run by [`Eroder`].

pub mod amplify;
pub mod diffusion;
pub mod stream_power;
pub mod thermal;
pub mod transport;

use serde::{Deserialize, Serialize};

use crate::analysis::flow::FlowGraph;
use crate::dem::{DemError, Heightfield};
use crate::value::{NonNegative, Positive};

pub use stream_power::StreamPower;
pub use thermal::ThermalReport;

/// Working memory of an [`Eroder`] per sample, bytes: elevations, receivers, lengths,
/// stack, donors (two arrays), drainage area, and the depression filling's flags and
/// queue.
pub const BYTES_PER_SAMPLE: u64 = 64;

/// Most steps a stream-power stage accepts.
pub const MAX_STEPS: u32 = 1_000_000;

fn default_m() -> NonNegative {
    NonNegative(0.4)
}

fn default_n() -> Positive {
    Positive(1.0)
}

fn default_tolerance() -> Positive {
    Positive(0.01)
}

fn default_iterations() -> u32 {
    10_000
}

/// Uplift and stream-power erosion, with optional hillslope diffusion and deposition:
/// `(steps: 200, dt: 20000, uplift: 0.001, k: 2e-4, m: 0.4, n: 1, diffusion: 0.01,
/// deposition: 1)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamPowerSpec {
    /// Time steps.
    pub steps: u32,
    /// Length of a step, years.
    pub dt: Positive,
    /// Uplift rate of every sample but base level, metres per year (default 0).
    #[serde(default)]
    pub uplift: NonNegative,
    /// Erodibility `K`.
    pub k: Positive,
    /// Drainage-area exponent `m` (default 0.4).
    #[serde(default = "default_m")]
    pub m: NonNegative,
    /// Slope exponent `n` (default 1).
    #[serde(default = "default_n")]
    pub n: Positive,
    /// Hillslope diffusivity `D`, m²/yr (default 0: none).
    #[serde(default)]
    pub diffusion: NonNegative,
    /// Deposition coefficient `G` of the sediment carried down (Yuan et al. 2019,
    /// [`transport`]; default 0: detachment-limited, what is cut leaves the grid).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub deposition: NonNegative,
}

fn is_zero(v: &NonNegative) -> bool {
    v.get() == 0.0
}

/// Thermal erosion down to a talus angle: `(talus: 35, tolerance: 0.01)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// Talus angle, degrees, in `(0, 90)`.
    pub talus: Positive,
    /// Stop when no drop exceeds the talus by more than this, metres (default 0.01).
    #[serde(default = "default_tolerance")]
    pub tolerance: Positive,
    /// Stop after this many passes in any case (default 10,000).
    #[serde(default = "default_iterations")]
    pub max_iterations: u32,
}

/// One stage of erosion, as tree files and `karstic erode` give it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ErosionStage {
    /// Uplift, stream power and diffusion.
    StreamPower(StreamPowerSpec),
    /// Talus-angle relaxation.
    Thermal(ThermalSpec),
}

impl ErosionStage {
    /// Checks the values a parser cannot (ranges between fields), naming the field.
    pub fn validate(&self) -> Result<(), DemError> {
        let bad = |what: String| Err(DemError::Invalid { what });
        match self {
            ErosionStage::StreamPower(s) if s.steps > MAX_STEPS => bad(format!(
                "StreamPower.steps: at most {MAX_STEPS}, got {}",
                s.steps
            )),
            ErosionStage::Thermal(t) if t.talus.get() >= 90.0 => bad(format!(
                "Thermal.talus: a slope angle in degrees below 90, got {}",
                t.talus
            )),
            _ => Ok(()),
        }
    }
}

/// A grid being eroded: the elevations and the flow graph's buffers, reused step to step.
#[derive(Debug)]
pub struct Eroder {
    hf: Heightfield,
    z: Vec<f32>,
    graph: FlowGraph,
    area: Vec<f32>,
    /// What a step cut (with deposition only).
    before: Vec<f32>,
}

impl Eroder {
    /// Starts from `hf`, refusing a grid whose working memory
    /// (`BYTES_PER_SAMPLE` a sample) is over `budget` bytes.
    pub fn new(hf: &Heightfield, budget: u64) -> Result<Eroder, DemError> {
        let n = hf.samples().len() as u64;
        crate::io::check_budget(
            format!("eroding a {}×{} grid", hf.nx(), hf.ny()),
            n.saturating_mul(BYTES_PER_SAMPLE),
            budget,
        )?;
        if u32::try_from(n).is_err() {
            return Err(DemError::Invalid {
                what: format!("a {}×{} grid is too large to erode", hf.nx(), hf.ny()),
            });
        }
        Ok(Eroder {
            hf: hf.clone(),
            z: hf.samples().to_vec(),
            graph: FlowGraph::new(),
            area: Vec::new(),
            before: Vec::new(),
        })
    }

    /// One step of a stream-power stage (its `steps` is not read).
    pub fn stream_power_step(&mut self, s: &StreamPowerSpec) {
        let (nx, ny, c) = (self.hf.nx(), self.hf.ny(), self.hf.cell());
        let law = StreamPower {
            k: s.k.get(),
            m: s.m.get(),
            n: s.n.get(),
        };
        let g = s.deposition.get();
        let rise = s.uplift.get() * s.dt.get();
        stream_power::route(&mut self.z, nx, ny, c.x, c.y, rise, &mut self.graph);
        self.graph.accumulate(c.x * c.y, &mut self.area);
        if g > 0.0 {
            self.before.clear();
            self.before.extend_from_slice(&self.z);
        }
        stream_power::incise(&mut self.z, &self.graph, &self.area, law, s.dt.get());
        if g > 0.0 {
            // what the step cut, in place of the heights before it; then where it settles
            for (b, &a) in self.before.iter_mut().zip(&self.z) {
                *b = (*b - a).max(0.0);
            }
            let cut = &self.before;
            transport::deposit(&mut self.z, &self.graph, &self.area, cut, c.x * c.y, g);
        }
        if s.diffusion.get() > 0.0 {
            diffusion::step(&mut self.z, nx, ny, c.x, c.y, s.diffusion.get(), s.dt.get());
        }
    }

    /// A thermal stage.
    pub fn thermal(&mut self, t: &ThermalSpec) -> ThermalReport {
        let (nx, ny, c) = (self.hf.nx(), self.hf.ny(), self.hf.cell());
        thermal::erode(
            &mut self.z,
            nx,
            ny,
            c.x,
            c.y,
            t.talus.get().to_radians(),
            t.tolerance.get(),
            t.max_iterations,
        )
    }

    /// Runs every stage in order.
    pub fn run(&mut self, stages: &[ErosionStage]) -> Result<(), DemError> {
        for s in stages {
            s.validate()?;
        }
        for s in stages {
            match s {
                ErosionStage::StreamPower(p) => {
                    for _ in 0..p.steps {
                        self.stream_power_step(p);
                    }
                }
                ErosionStage::Thermal(t) => {
                    self.thermal(t);
                }
            }
        }
        Ok(())
    }

    /// The current elevations.
    pub fn samples(&self) -> &[f32] {
        &self.z
    }

    /// The eroded heightfield (same origin and cells as the input); an error if extreme
    /// parameters drove an elevation to infinity.
    pub fn heightfield(&self) -> Result<Heightfield, DemError> {
        Heightfield::new(
            self.hf.nx(),
            self.hf.ny(),
            self.hf.origin(),
            self.hf.cell(),
            self.z.clone(),
        )
    }
}
