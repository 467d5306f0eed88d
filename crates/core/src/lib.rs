//! The core of karstic: the field contract (an implicit construction tree and what its
//! nodes answer: values, gradients, bounds), the file format's value types, a seeded
//! random stream, and the I/O plumbing every part shares.

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cache;
pub mod field;
pub mod io;
pub mod rng;
pub mod value;
