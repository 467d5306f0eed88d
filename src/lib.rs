//! karstic: terrain modelling with implicit construction trees.
//!
//! A DEM becomes an implicit primitive, Feature Curves become an S-field primitive, and
//! both combine with skeletal primitives through blend, carve and warp nodes. The compiled
//! [`field`] tree is the single thing the mesher and the tracers consume.

// `!(a < b)` is how this crate says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod analysis;
mod cache;
pub mod compile;
pub mod curves;
pub mod dem;
pub mod editor;
pub mod elevation;
pub mod erosion;
pub mod field;
pub mod geology;
pub mod heightmap;
pub mod io;
pub mod job;
pub mod landform;
pub mod mesh;
pub mod picture;
pub mod procedural;
pub mod render;
pub mod rng;
pub mod scene;
pub mod tape;
pub mod tiles;
pub mod value;
pub mod voxel;
