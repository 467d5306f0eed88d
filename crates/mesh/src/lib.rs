//! Polygonization: bound-pruned Marching Cubes over any field, dense grids and heightfield
//! TINs, the indexed mesh, and its exporters (glTF, OBJ, PLY).

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod mesh;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{cache, field, io};
use karstic_dem::dem;
