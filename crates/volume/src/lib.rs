//! Feature Volumes: Feature Curves and the other modelling primitives of Becher 2016,
//! and the sparse voxel pipeline that diffuses them into the S-field leaf.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod curves;
pub mod voxel;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io, value};
use karstic_mesh::mesh;
