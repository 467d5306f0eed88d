//! The nodes of the compiled tree: leaves and the operators of Paris et al. 2019 §5.3.

use std::sync::Arc;

use glam::{Affine3A, Mat3A};

use super::bvh::ChildBvh;
use super::contract::Field;
use super::erode::Erosion;
use super::primitive::Primitive;
use super::replace::Transition;
use super::warp::Warp;

/// Index of a node in a [`super::Tree`] arena. Children always have smaller ids than their
/// parents (post-order), and a node may have several parents (instancing).
pub type NodeId = u32;

/// One node of the arena.
pub enum Node {
    /// A constant field (appears when pruning folds a subtree).
    Constant(f32),
    /// A skeletal primitive, stored inline so evaluating it chases no pointer.
    Primitive(Primitive),
    /// Any other leaf: heightfield, S-field volume, …
    Leaf(Arc<dyn Field>),
    /// n-ary blend: `Σ fᵢ` (Wyvill). Many children get a BVH over their supports.
    Blend {
        /// Children.
        children: Box<[NodeId]>,
        /// Present when there are enough children to pay for it.
        bvh: Option<ChildBvh>,
    },
    /// Union: `max fᵢ`.
    Union(Box<[NodeId]>),
    /// Intersection: `min fᵢ`.
    Intersection(Box<[NodeId]>),
    /// Difference (carve): `min(f_base, 2T − f_c₁, 2T − f_c₂, …)`.
    Difference {
        /// What is carved.
        base: NodeId,
        /// What carves it.
        carves: Box<[NodeId]>,
    },
    /// Affine warp: `f(p) = f_child(M⁻¹p)`, with `M` the child-to-parent map.
    Affine {
        /// The transformed subtree.
        child: NodeId,
        /// `M⁻¹`: parent space to child space.
        to_child: Affine3A,
        /// `‖M⁻¹‖₂`, the factor on the child's Lipschitz bounds.
        stretch: f32,
    },
    /// Replacement: `f_base + w·(f_by − f_base)`, `w` the partition of unity of a region
    /// ([`Transition`]): the base outside the region, `by` in its core.
    Replace {
        /// What is replaced (the terrain).
        base: NodeId,
        /// What stands in for it inside the region.
        by: NodeId,
        /// The region and its transition.
        mix: Box<Transition>,
    },
    /// Localized turbulence warp `f(p) = f_child(p + δ(p)·f_D(p))` (Paris et al. 2019 §5.3).
    Warp {
        /// The warped subtree.
        child: NodeId,
        /// δ and f_D.
        warp: Box<Warp>,
    },
    /// Erosion by the geology `f(p) = f_child(p) − f_D(p)·(1 − ρ(p))` over a region
    /// (Paris et al. 2019 §6).
    Erode {
        /// The eroded subtree.
        child: NodeId,
        /// The region, its strength and the geology.
        erosion: Box<Erosion>,
    },
}

impl Node {
    /// The field of a leaf (primitive or other), `None` for constants and operators.
    #[inline]
    pub fn leaf(&self) -> Option<&dyn Field> {
        match self {
            Node::Primitive(p) => Some(p),
            Node::Leaf(f) => Some(&**f),
            _ => None,
        }
    }

    /// The children, in order.
    pub fn children(&self) -> Vec<NodeId> {
        match self {
            Node::Constant(_) | Node::Primitive(_) | Node::Leaf(_) => Vec::new(),
            Node::Blend { children, .. } | Node::Union(children) | Node::Intersection(children) => {
                children.to_vec()
            }
            Node::Difference { base, carves } => std::iter::once(*base)
                .chain(carves.iter().copied())
                .collect(),
            Node::Replace { base, by, .. } => vec![*base, *by],
            Node::Affine { child, .. } | Node::Warp { child, .. } | Node::Erode { child, .. } => {
                vec![*child]
            }
        }
    }

    /// A short name of the node's kind.
    pub fn kind(&self) -> &'static str {
        match self {
            Node::Constant(_) => "constant",
            Node::Primitive(_) => "primitive",
            Node::Leaf(_) => "leaf",
            Node::Blend { .. } => "blend",
            Node::Union(_) => "union",
            Node::Intersection(_) => "intersection",
            Node::Difference { .. } => "difference",
            Node::Replace { .. } => "replace",
            Node::Affine { .. } => "transform",
            Node::Warp { .. } => "warp",
            Node::Erode { .. } => "erode",
        }
    }
}

/// Spectral norm of a 3×3 matrix (its largest singular value), padded so it is an upper
/// bound: the square root of the largest eigenvalue of the symmetric `MᵀM`, in closed form.
pub fn spectral_norm(m: Mat3A) -> f32 {
    let a = m.transpose() * m;
    let (a00, a11, a22) = (a.x_axis.x as f64, a.y_axis.y as f64, a.z_axis.z as f64);
    let (a01, a02, a12) = (a.y_axis.x as f64, a.z_axis.x as f64, a.z_axis.y as f64);
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let largest = if p1 < 1e-30 {
        a00.max(a11).max(a22)
    } else {
        let q = (a00 + a11 + a22) / 3.0;
        let p2 = (a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * p1;
        let p = (p2 / 6.0).sqrt();
        let (b00, b11, b22) = ((a00 - q) / p, (a11 - q) / p, (a22 - q) / p);
        let (b01, b02, b12) = (a01 / p, a02 / p, a12 / p);
        let det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
            + b02 * (b01 * b12 - b11 * b02);
        let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
        q + 2.0 * p * phi.cos()
    };
    (largest.max(0.0).sqrt() * (1.0 + 1e-5) + 1e-7) as f32
}
