//! Elevation trees (Génevaux et al. 2015): 2.5D construction trees of terrain primitives,
//! a leaf of the field.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod elevation;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, value};
use karstic_dem::dem;
