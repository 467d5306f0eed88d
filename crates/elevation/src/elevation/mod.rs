//! Elevation trees: the 2.5D construction trees of Génevaux et al. 2015.
//!
//! A tree's nodes map a point of the plane to an elevation `f` and a weight `α`
//! (Génevaux et al. 2015 §3): primitives (discs with multifractal elevations, curves with
//! cross-sections, contours with profiles, raster images; `primitive.rs`,
//! `multifractal.rs`) are combined by operators (blend, add, replace, warp; `node.rs`),
//! with continuous level of detail (`lod.rs`) and bounds over rectangles — ranges and
//! Lipschitz bounds of `f` and `α` (`bounds.rs`). A large blend indexes its children's
//! supports in a grid (`index.rs`), so a query touches few primitives.
//!
//! A tree enters the 3D world through [`ElevationField`], the implicitization of Paris et
//! al. 2019 §5.1 over an elevation function instead of a raster: no grid in between, so it
//! can be meshed at any cell size. Tree files write it as an `Elevation(...)` leaf
//! (`spec.rs`, `docs/elevation-trees.md`).

mod bounds;
pub mod geometry;
mod index;
pub mod leaf;
pub mod lod;
pub mod multifractal;
pub mod node;
pub mod primitive;
pub mod profile;
pub mod spec;

use glam::Vec2;
use rayon::prelude::*;

pub use bounds::Bounds;
pub use leaf::{ElevationField, ElevationParams};
pub use lod::Lod;
pub use node::Node;
pub use primitive::Sample;
pub use spec::{BuildContext, ENodeSpec, ElevationSpec};

use crate::field::Rect;

/// Errors building an elevation tree or its leaf.
#[derive(Debug, thiserror::Error)]
pub enum ElevationError {
    /// A node of the tree is wrong; `at` is its path (`tree.children[2] (Curve)`).
    #[error("elevation tree node {at}: {what}")]
    Node {
        /// The node's path and kind.
        at: String,
        /// What is wrong.
        what: String,
    },
    /// The leaf's parameters are wrong.
    #[error("elevation leaf: {0}")]
    Leaf(String),
}

/// Fewest and most points per rayon task in [`ElevationTree::heights`].
const BATCH: (usize, usize) = (4096, 65536);

/// An elevation tree: its root node.
#[derive(Clone, Debug)]
pub struct ElevationTree {
    root: Node,
}

impl ElevationTree {
    /// The tree rooted at `root`.
    pub fn new(root: Node) -> ElevationTree {
        ElevationTree { root }
    }

    /// `(f(p), α(p))`.
    #[inline]
    pub fn eval(&self, p: Vec2, lod: &Lod) -> Sample {
        self.root.eval(p, lod)
    }

    /// The elevation `f(p)`.
    #[inline]
    pub fn height(&self, p: Vec2, lod: &Lod) -> f32 {
        self.root.eval(p, lod).f
    }

    /// Elevations of many points, in parallel: `out[i] = f(points[i])`.
    /// The points go to each thread in a few large chunks: a blend's batch shares the
    /// work on the points that fall in the same cell of its index.
    pub fn heights(&self, points: &[Vec2], lod: &Lod, out: &mut [f32]) {
        let chunk =
            (points.len().div_ceil(4 * rayon::current_num_threads())).clamp(BATCH.0, BATCH.1);
        out.par_chunks_mut(chunk)
            .zip(points.par_chunks(chunk))
            .for_each(|(o, p)| self.root.heights(p, lod, o));
    }

    /// Bounds of `f` and `α` over `r`.
    pub fn bounds(&self, r: &Rect, lod: &Lod) -> Bounds {
        self.root.bounds(r, lod)
    }

    /// The box outside which the root's weight is 0 (its elevation is still defined).
    pub fn support(&self) -> Rect {
        self.root.support()
    }
}
