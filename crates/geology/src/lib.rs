//! Geology: the rock's resistance to erosion as a construction tree of its own (Paris et
//! al. 2019 §4), which the erosion node and the landform generators read.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod geology;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io, value};
