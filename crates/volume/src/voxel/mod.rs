//! The voxel pipeline of Becher 2016 (ch. 4) on a sparse, multi-level grid, and the S-field
//! primitive it produces ([`SField`]).

pub mod cache;
pub mod diffuse;
pub mod expand;
pub mod extract;
pub mod pipeline;
pub mod propagate;
pub mod sfield;
pub mod smooth;
pub mod sparse;
pub mod spec;
pub mod tricubic;
pub mod voxelize;

pub use cache::run_cached;
pub use expand::{Expanded, Expansion, expand};
pub use pipeline::{Params, Stats, Volume, run};
pub use sfield::{FieldParams, SField};
pub use spec::{FeatureSet, FeatureVolumeSpec};
pub use tricubic::Interpolation;
