//! Tree files and what runs them: the file format, terrain analysis and erosion, the
//! landform generators, the compiler, the one picture setup, the main job and the tiles.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod analysis;
pub mod compile;
pub mod erosion;
pub mod heightmap;
pub mod job;
pub mod landform;
pub mod picture;
pub mod procedural;
pub mod scene;
pub mod tiles;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io, rng, value};
use karstic_dem::dem;
use karstic_elevation::elevation;
use karstic_geology::geology;
use karstic_mesh::mesh;
use karstic_render::render;
use karstic_volume::voxel;
