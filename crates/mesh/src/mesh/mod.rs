//! Polygonization: bound-pruned Marching Cubes over fields and dense grids, the indexed
//! mesh it produces, and its exporters (Paris et al. 2019 §7).
//!
//! * [`polygonize`] extracts the surface `f = T` of any [`crate::field::Field`] on a
//!   [`GridSpec`], evaluating only the samples of cells inside the field's z-bands and
//!   reading heights straight from elevations where the field is a heightfield.
//! * [`mc_dense`] extracts an iso-surface of a precomputed grid (e.g. an `.npy` volume).
//!
//! Both produce a welded, crack-free, consistently oriented [`Mesh`]; see
//! `docs/meshing.md`.

pub mod cell;
pub mod columns;
pub mod dense;
mod estimate;
pub mod export;
pub mod grid;
pub mod indexed;
pub mod npy;
pub mod polygonize;
pub mod sample;
pub mod stats;
pub mod tables;
pub mod tin;

pub use dense::{DenseGrid, mc_dense};
pub use grid::GridSpec;
pub use indexed::{Attribute, Mesh, Topology, TopologyError};
pub use polygonize::{MeshOptions, polygonize};
pub use stats::MeshStats;

/// Errors of the mesher and its exporters.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A grid whose shape or spacing cannot be meshed.
    #[error("bad grid: {0}")]
    GridShape(String),
    /// The extraction would exceed the memory budget.
    #[error(transparent)]
    Budget(#[from] crate::io::IoError),
}

/// Splits `v` into consecutive mutable parts of the given lengths.
pub(crate) fn split_parts<'v, T>(mut v: &'v mut [T], lens: &[usize]) -> Vec<&'v mut [T]> {
    let mut parts = Vec::with_capacity(lens.len());
    for &n in lens {
        let (head, tail) = v.split_at_mut(n);
        parts.push(head);
        v = tail;
    }
    parts
}

/// The parts one after the other, copied in parallel into one allocation.
pub(crate) fn par_concat<'p, T: Copy + Default + Send + Sync + 'p>(
    parts: impl Iterator<Item = &'p [T]>,
) -> Vec<T> {
    use rayon::prelude::*;
    let parts: Vec<&[T]> = parts.collect();
    let lens: Vec<usize> = parts.iter().map(|p| p.len()).collect();
    let mut out = vec![T::default(); lens.iter().sum()];
    split_parts(&mut out, &lens)
        .into_par_iter()
        .zip(parts)
        .for_each(|(dst, src)| dst.copy_from_slice(src));
    out
}
