//! Helpers shared by the test suites (and, through `#[path]`, the benches), one file per
//! concern: the seeded random generator; small test fields for the renderer (a σ-sphere
//! with analytic ground truth, a sum of many Wyvill point blobs with local Lipschitz
//! bounds from a grid, a heightfield-like terrain chunk) and their GPU tapes; the
//! Jacksboro DEM; bound, z-band and image checks; the GPU context; and the switch that makes a
//! missing optional tool (GPU adapter, glTF validator, trimesh, Slurm) a failure.

pub mod dem;
pub mod tapes;

mod blobs;
mod frames;
mod gpu;
mod lipschitz;
mod optional;
mod rng;
mod sphere;
mod terrain;
mod trimesh;
mod uv_sphere;
mod z_bands;

pub use blobs::Blobs;
pub use frames::{assert_frames_match, assert_frames_match_within, depth_agreement};
pub use gpu::{assert_probes_match, gpu};
pub use lipschitz::check_segment_lipschitz;
pub use optional::{REQUIRE_GDAL, REQUIRE_GLTF_VALIDATOR, REQUIRE_GPU, REQUIRE_SLURM, unavailable};
pub use rng::Rng;
pub use sphere::SigmaSphere;
pub use terrain::Terrain;
pub use trimesh::{trimesh_import, trimesh_version};
pub use uv_sphere::uv_sphere;
pub use z_bands::{check_z_bands, column_crossings_in_bands};

/// The eye and target of the main job's view into its tunnel's mouth (the one
/// `karstic run trees/jacksboro_caves.ron` frames).
pub const TUNNEL_VIEW: (glam::Vec3, glam::Vec3) = (
    glam::Vec3::new(3641.5, 4961.8, 867.7),
    glam::Vec3::new(3542.5, 4956.4, 854.6),
);
