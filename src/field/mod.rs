//! The compiled implicit construction tree and what its nodes answer.

pub mod bounds;
pub mod contract;
pub mod falloff;
pub mod noise;
pub mod primitive;
pub mod skeleton;

pub use bounds::{Aabb, Interval, Rect, ZBands};
pub use contract::{Elevation, ElevationSource, Field};
pub use falloff::T;
pub use noise::{Fbm, NoiseSpec};
pub use primitive::{Noise, Primitive, PrimitiveError, PrimitiveSpec};
pub use skeleton::{Skeleton, SkeletonSpec};
