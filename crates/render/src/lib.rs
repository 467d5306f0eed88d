//! Pictures of a field: the CPU ray tracer, shading and materials, and the GPU tracer
//! (wgpu) over the tree lowered to a tape.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod render;
pub mod tape;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io};
use karstic_dem::dem;
use karstic_elevation::elevation;
use karstic_geology::geology;
use karstic_mesh::mesh;
use karstic_volume::{curves, voxel};
