//! `karstic edit`: the interactive editor of a tree file (egui, on eframe's wgpu
//! renderer).

// `!(a < b)` is how karstic says "not less, or NaN": the negation is the point.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod editor;

// The layers below, under the paths this crate's modules name them by.
use karstic_core::{field, io, value};
use karstic_dem::dem;
use karstic_render::{render, tape};
use karstic_scene::{compile, job, picture, scene};
use karstic_volume::voxel;
