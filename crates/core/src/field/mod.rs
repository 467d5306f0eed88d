//! The compiled implicit construction tree and what its nodes answer.
//!
//! Layout follows fidget's split: building ([`TreeBuilder`], the scene compiler), the flat
//! arena ([`Tree`], [`node`]), and the evaluators (point values and gradients in `eval`,
//! box bounds in `box_bounds`, z-bands in `zband`, pruning in `prune`, grids in [`grid`]).

mod batch;
mod block;
pub mod bound;
pub mod bounds;
mod box_bounds;
pub mod bvh;
pub mod contract;
mod erode;
mod eval;
pub mod falloff;
pub mod grid;
pub mod lanes;
mod line;
pub mod node;
pub mod noise;
mod point_grid;
pub mod primitive;
mod profile;
mod prune;
pub mod replace;
pub mod skeleton;
mod slope_grid;
mod tree;
pub mod warp;
mod zband;

pub use block::BRICK;
pub use bound::Bound;
pub use bounds::{Aabb, Interval, Rect, ZBands};
pub use box_bounds::map_box;
pub use contract::{Elevation, ElevationSource, Field};
pub use erode::{Erosion, Resistance};
pub use falloff::ISO;
pub use grid::{Grid, eval_grid, eval_grid_naive, slab_count};
pub use line::Line;
pub use node::{Node, NodeId};
pub use noise::{Fbm, NoiseSpec};
pub use primitive::{Noise, Primitive, PrimitiveError, PrimitiveSpec};
pub use profile::LineProfile;
pub use replace::Transition;
pub use skeleton::{Skeleton, SkeletonSpec};
pub use tree::{NodeInfo, SubTree, Tree, TreeBuilder};
pub use warp::Warp;
