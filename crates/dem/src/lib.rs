//! Digital elevation models: readers and writers, the heightfield grid and its implicit
//! leaf (Paris et al. 2019 §5.1).

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod dem;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io};
