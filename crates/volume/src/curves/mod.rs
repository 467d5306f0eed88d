//! Feature Curves and the other modelling primitives of Becher 2016 (ch. 3): cubic
//! B-splines with Constraint Points, simple shapes, compound tunnels and arches, and the
//! proxy ribbon meshes they all turn into for the voxel pipeline.

pub mod bspline;
pub mod compound;
pub mod constraint;
pub mod ribbon;
pub mod room;
pub mod shapes;
pub mod terrain;

use std::path::PathBuf;

use glam::Vec3;
use serde::{Deserialize, Serialize};

pub use bspline::BSpline;
pub use compound::{Arch, Profile, Tube, Tunnel, tube_proxy, tunnel_proxies};
pub use constraint::{ConstraintPoint, CurveSample, FeatureCurve, slope_bitangent};
pub use ribbon::{ProxyMesh, ProxyTriangle, ProxyVertex, Side, curve_ribbon};
pub use room::Room;
pub use shapes::{Disc, Quad};
pub use terrain::TerrainSurface;

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
    /// A file cannot be read as asked (not a regular file, larger than allowed), or the
    /// grids would exceed the memory budget.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
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
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
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
    /// The terrain the primitives sit on, as boundary conditions: its seed triangles join
    /// the proxy meshes, and compounds keep only their side of it (a tunnel what is
    /// underground, an arch what is above).
    pub terrain: Option<TerrainSurface>,
}

impl Features {
    /// Tunnels whose section is at least `min_section` metres (smaller ones are left out
    /// of coarse levels, whose cells would hold their floor and ceiling at once).
    pub fn tunnels_from(&self, min_section: f32) -> Vec<Tube> {
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
        let thin_arch = self.arches.iter().any(|a| a.beam().section() < min_section);
        if thin_arch && !thin_tunnel { 1.0 } else { -1.0 }
    }

    /// True when some seed primitive is present once tunnels and arch beams thinner than
    /// `min_section` are left out.
    pub fn has_seed(&self, min_section: f32) -> bool {
        self.curves.iter().any(|c| c.seed)
            || self
                .arches
                .iter()
                .any(|a| a.ground.is_some() || a.beam().section() >= min_section)
            || self.quads.iter().any(|q| q.seed)
            || self.discs.iter().any(|d| d.seed)
            || self.meshes.iter().any(|m| m.has_seed())
            || self.tunnels.iter().any(|t| t.section() >= min_section)
            || self.terrain.as_ref().is_some_and(|t| t.mesh().has_seed())
    }

    /// Where a tunnel's curves are kept: on a terrain, deeper than its clearance
    /// underground (where the ground is known); everywhere otherwise.
    fn tunnel_side(&self, p: Vec3) -> bool {
        self.terrain
            .as_ref()
            .is_none_or(|t| !t.above(p, -t.clearance()))
    }

    /// Where an arch's curves are kept: on a terrain, higher than its clearance above
    /// ground (where the ground is known); everywhere otherwise.
    fn arch_side(&self, p: Vec3) -> bool {
        self.terrain
            .as_ref()
            .is_none_or(|t| !t.below(p, -t.clearance()))
    }

    /// All primitives as one proxy mesh: ribbons `ribbon` metres wide unless a curve sets
    /// its own, continued by guidance triangles up to `guide` metres, segments no longer
    /// than `segment` (a voxel or less); tunnels with a section and arch beams with a
    /// thickness under `min_section` are left out.
    pub fn proxy(&self, ribbon: f32, guide: f32, segment: f32, min_section: f32) -> ProxyMesh {
        let mut mesh = ProxyMesh::default();
        let all = |_: Vec3| true;
        let guide = guide.max(ribbon);
        for c in &self.curves {
            let w = c.ribbon.unwrap_or(ribbon);
            mesh.append(&curve_ribbon(c, w, guide.max(w), segment, &all));
        }
        for a in &self.arches {
            let beam = a.beam();
            if beam.section() >= min_section {
                let keep = |p: Vec3| self.arch_side(p);
                mesh.append(&tube_proxy(&beam, ribbon, guide, segment, &keep));
            }
            if let Some(c) = a.ground_curve() {
                mesh.append(&curve_ribbon(&c, ribbon, guide, segment, &all));
            }
        }
        let keep = |p: Vec3| self.tunnel_side(p);
        mesh.append(&tunnel_proxies(
            &self.tunnels_from(min_section),
            ribbon,
            guide,
            segment,
            &keep,
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
        if let Some(t) = &self.terrain {
            mesh.append(t.mesh());
        }
        mesh
    }

    /// Samples every `step` metres of every seed curve (those the compounds place
    /// included, junctions of tunnels and, on a terrain, the compounds' parts on the
    /// wrong side of the ground left out): where the surface must pass.
    pub fn seed_samples(&self, step: f32, ribbon: f32) -> Vec<CurveSample> {
        let mut out = Vec::new();
        let mut push = |c: &FeatureCurve, keep: &dyn Fn(Vec3) -> bool| {
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
        for a in &self.arches {
            a.beam()
                .curves()
                .iter()
                .for_each(|c| push(c, &|p| self.arch_side(p)));
            a.ground_curve().iter().for_each(|c| push(c, &|_| true));
        }
        for (i, t) in self.tunnels.iter().enumerate() {
            for c in t.curves() {
                push(&c, &|p| {
                    self.tunnel_side(p) && compound::outside_others(&self.tunnels, i, p, ribbon)
                });
            }
        }
        out
    }

    /// Every tube: the tunnels, then the arches' slabs.
    fn tubes(&self) -> impl Iterator<Item = Tube> + '_ {
        self.tunnels
            .iter()
            .cloned()
            .chain(self.arches.iter().map(Arch::beam))
    }

    /// The largest noise roughness β of the primitives (0 without noise).
    pub fn max_roughness(&self) -> f32 {
        let curves = self
            .curves
            .iter()
            .flat_map(|c| c.constraints.iter().map(|k| k.roughness));
        let tubes = self.tunnels.iter().map(|t| t.noise.y);
        let arches = self.arches.iter().map(|a| a.noise.y);
        let shapes = self.quads.iter().map(|q| q.noise.y);
        let discs = self.discs.iter().map(|d| d.noise.y);
        let meshes = self
            .meshes
            .iter()
            .flat_map(|m| m.vertices.iter().map(|v| v.noise.y));
        curves
            .chain(tubes)
            .chain(arches)
            .chain(shapes)
            .chain(discs)
            .chain(meshes)
            .fold(0.0, f32::max)
    }

    /// Balls around the tubes (tunnels, arch beams) whose section lies in
    /// `[min_section, 2·min_section)`, grown by `margin`: those that first appear on a
    /// level admitting sections of `min_section` (the coarser one admits twice that).
    /// The guidance the coarser levels diffused there knows nothing of them.
    pub fn fresh_room(&self, min_section: f32, margin: f32) -> Room {
        let fresh = |t: &Tube| (min_section..2.0 * min_section).contains(&t.section());
        let mut out = Vec::new();
        for tube in self.tubes().filter(fresh) {
            out.extend(
                tube.balls(min_section / 3.0)
                    .into_iter()
                    .map(|(p, r)| (p, r + margin)),
            );
        }
        Room::new(out)
    }

    /// Balls in which a terrain's samples give way to the primitives: around every seed
    /// curve (radius `ribbon + clearance`), and around the axis of every tube on its side
    /// of the ground (radius: half the section's larger side plus `clearance`), with
    /// `step` metres between samples.
    pub fn room(&self, step: f32, ribbon: f32, clearance: f32) -> Room {
        let mut out: Vec<(Vec3, f32)> = self
            .seed_samples(step, ribbon)
            .iter()
            .map(|s| (s.pos, ribbon + clearance))
            .collect();
        for tube in self.tubes() {
            let side = |p: Vec3| {
                if tube.inward {
                    self.tunnel_side(p)
                } else {
                    self.arch_side(p)
                }
            };
            out.extend(
                tube.balls(step)
                    .into_iter()
                    .filter(|&(p, _)| side(p))
                    .map(|(p, r)| (p, r + clearance)),
            );
        }
        for q in self.quads.iter().filter(|q| q.seed) {
            let c = q.corners.iter().sum::<Vec3>() / 4.0;
            let r = q.corners.iter().map(|p| p.distance(c)).fold(0.0, f32::max);
            out.push((c, r + clearance));
        }
        for d in self.discs.iter().filter(|d| d.seed) {
            out.push((d.center, d.radius + clearance));
        }
        Room::new(out)
    }
}

/// Which side of the surface the primitive's field is solid on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Orientation {
    /// Solid behind the surface (opposite the normals): `f = σ(−S)`. Rock, ground.
    #[default]
    Solid,
    /// Solid on the normals' side: `f = σ(S)`. The air of a cave, to carve with.
    Air,
}

/// Surface propagation method (Becher 2016 §4.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Propagation {
    /// Signed distance propagation (§4.6.2).
    #[default]
    Distance,
    /// Streamlines along the bitangent field add surface cells first (§4.6.1), then the
    /// distance propagation signs the field.
    Streamline,
}
