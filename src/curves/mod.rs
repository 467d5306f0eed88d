//! Feature Curves and the other modelling primitives of seed 000 (ch. 3): cubic
//! B-splines with Constraint Points, simple shapes, compound tunnels and arches, and the
//! proxy ribbon meshes they all turn into for the voxel pipeline ([`crate::voxel`]).

pub mod bspline;
pub mod compound;
pub mod constraint;
pub mod ribbon;
pub mod shapes;
pub mod spec;

use std::path::PathBuf;

pub use bspline::BSpline;
pub use compound::{Arch, Profile, Tunnel, tunnel_proxies};
pub use constraint::{ConstraintPoint, CurveSample, FeatureCurve, slope_bitangent};
pub use ribbon::{ProxyMesh, ProxyTriangle, ProxyVertex, Side, curve_ribbon};
pub use shapes::{Disc, Quad};
pub use spec::{FeatureSet, FeatureVolumeSpec, Orientation, Propagation};

/// Errors of curve files, feature-volume specs and the voxel pipeline.
#[derive(Debug, thiserror::Error)]
pub enum CurveError {
    /// A file could not be read.
    #[error("cannot read {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A RON file does not parse.
    #[error("{path}:{line}:{col}: {msg}")]
    Parse {
        /// The file (or `<inline>`).
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What was expected.
        msg: String,
    },
    /// A value parses but makes no sense (names the primitive and the field).
    #[error("{what}: {msg}")]
    Invalid {
        /// Which primitive and field, e.g. `curve "ridge" constraint 2`.
        what: String,
        /// What is wrong.
        msg: String,
    },
    /// The grids would exceed the memory budget.
    #[error(transparent)]
    Budget(#[from] crate::io::IoError),
}

impl CurveError {
    /// An [`CurveError::Invalid`] error.
    pub fn invalid(what: impl Into<String>, msg: impl Into<String>) -> Self {
        CurveError::Invalid {
            what: what.into(),
            msg: msg.into(),
        }
    }
}

/// Resolved modelling primitives: what a [`FeatureSet`] file describes, in world
/// coordinates, ready to become proxy meshes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    /// Feature Curves.
    pub curves: Vec<FeatureCurve>,
    /// Quads.
    pub quads: Vec<Quad>,
    /// Discs.
    pub discs: Vec<Disc>,
    /// Tunnels (those sharing nodes open into each other).
    pub tunnels: Vec<Tunnel>,
    /// Arches.
    pub arches: Vec<Arch>,
    /// Extra proxy triangles (any mesh with normals).
    pub meshes: Vec<ProxyMesh>,
}

impl Features {
    /// Tunnels whose section is at least `min_section` metres (smaller ones are left out
    /// of coarse levels, whose cells would hold their floor and ceiling at once).
    pub fn tunnels_from(&self, min_section: f32) -> Vec<Tunnel> {
        self.tunnels
            .iter()
            .filter(|t| t.section() >= min_section)
            .cloned()
            .collect()
    }

    /// Which side of the surface lies far from the primitives that are too thin for a
    /// grid of cells `min_section / 3` (those [`Features::proxy`] leaves out): rock
    /// (`-1`) around thin tunnels, air (`+1`) around thin arch beams when no tunnel is
    /// thin. Levels before the first one with a seed hold a constant S of this sign.
    pub fn outside_of_thin(&self, min_section: f32) -> f32 {
        let thin_tunnel = self.tunnels.iter().any(|t| t.section() < min_section);
        let thin_arch = self.arches.iter().any(|a| a.thickness < min_section);
        if thin_arch && !thin_tunnel { 1.0 } else { -1.0 }
    }

    /// True when some seed primitive is present once tunnels and arch beams thinner than
    /// `min_section` are left out.
    pub fn has_seed(&self, min_section: f32) -> bool {
        self.curves.iter().any(|c| c.seed)
            || self
                .arches
                .iter()
                .any(|a| a.ground.is_some() || a.thickness >= min_section)
            || self.quads.iter().any(|q| q.seed)
            || self.discs.iter().any(|d| d.seed)
            || self.meshes.iter().any(|m| m.has_seed())
            || self.tunnels.iter().any(|t| t.section() >= min_section)
    }

    /// All primitives as one proxy mesh: ribbons `ribbon` metres wide unless a curve sets
    /// its own, continued by guidance triangles up to `guide` metres, segments no longer
    /// than `segment` (a voxel or less); tunnels with a section and arch beams with a
    /// thickness under `min_section` are left out.
    pub fn proxy(&self, ribbon: f32, guide: f32, segment: f32, min_section: f32) -> ProxyMesh {
        let mut mesh = ProxyMesh::default();
        let all = |_: glam::Vec3| true;
        for c in &self.curves {
            let w = c.ribbon.unwrap_or(ribbon);
            mesh.append(&curve_ribbon(c, w, guide.max(w), segment, &all));
        }
        for a in &self.arches {
            for c in a.curves_at(min_section) {
                mesh.append(&curve_ribbon(&c, ribbon, guide.max(ribbon), segment, &all));
            }
        }
        mesh.append(&tunnel_proxies(
            &self.tunnels_from(min_section),
            ribbon,
            guide.max(ribbon),
            segment,
        ));
        for q in &self.quads {
            mesh.append(&q.proxy());
        }
        for d in &self.discs {
            mesh.append(&d.proxy(segment));
        }
        for m in &self.meshes {
            mesh.append(m);
        }
        mesh
    }

    /// Samples every `step` metres of every seed curve (those the compounds place
    /// included, junctions of tunnels left out): where the surface must pass.
    pub fn seed_samples(&self, step: f32, ribbon: f32) -> Vec<CurveSample> {
        let mut out = Vec::new();
        let mut push = |c: &FeatureCurve, keep: &dyn Fn(glam::Vec3) -> bool| {
            if c.seed {
                let n = ((c.spline.length(64) / step).ceil() as usize).max(1);
                out.extend(
                    (0..=n)
                        .map(|i| c.sample(i as f32 / n as f32))
                        .filter(|s| keep(s.pos)),
                );
            }
        };
        self.curves.iter().for_each(|c| push(c, &|_| true));
        self.arches
            .iter()
            .flat_map(|a| a.curves())
            .for_each(|c| push(&c, &|_| true));
        for (i, t) in self.tunnels.iter().enumerate() {
            for c in t.curves() {
                push(&c, &|p| {
                    compound::outside_others(&self.tunnels, i, p, ribbon)
                });
            }
        }
        out
    }
}
