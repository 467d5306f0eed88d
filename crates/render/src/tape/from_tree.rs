//! The builder from a compiled [`Tree`]: encoding it as a GPU [`Tape`]: a depth-first walk of its arena that
//! emits every node through the [`TapeBuilder`], reproducing the tree's values exactly
//! (up to float rounding).
//!
//! | tree node | tape |
//! | --- | --- |
//! | constant | `CONST` |
//! | [`Primitive`] on a point, segment, sphere, capsule, axis-aligned box, cone or ellipsoid | `PRIM` (Wyvill); `NPRIM` with noise |
//! | [`Primitive`] on a polyline or curve | its segments' `PRIM`s (`NPRIM`s) under a BVH of guards, combined by `UNION` (`E ≥ 0`: `E·g(minᵢ d̃ᵢ) = maxᵢ E·g(d̃ᵢ)`, `g` decreasing) or `INTER` (`E < 0`) |
//! | [`HeightfieldField`] (bilinear or bicubic, square cells, no nodata, no domain polygon) | `HEIGHT` ∩ `PRIM` on its [`Shape::Prism`], energy `2T`: `min(σ(h − z), 2T·g(d_P/R))` as the leaf defines it |
//! | [`SField`] (a `FeatureVolume`) | `SFIELD` over its bricks ([`super::sfield`]) |
//! | blend | children chained by `BLEND`; with a BVH (many children), [`TapeBuilder::combine_bvh`] over the children's supports |
//! | union / intersection | children chained by `UNION` / `INTER` |
//! | difference | base, then each carve and `DIFF` |
//! | affine transform | `WARP`, child, `UNWARP` with the tree's own `M⁻¹` |
//! | turbulence warp | `TWARP`, child, `UNWARP` (the tree's bound: the child's over the ball grown by the warp's reach, times its Lipschitz bound) |
//! | erosion by a geology (`Erode`) | none: [`TapeError::NoEncoding`], the CPU renders it |
//!
//! Every emitted subtree is then told its support from the tree's cache
//! ([`TapeBuilder::assume_support`]), so the tape's guards and support box are the tree's;
//! S-field volumes and noisy primitives get a guard of their own (their evaluation is
//! long, and rays away from them jump over it).
//! A node with no encoding — a disc, plane or prism skeleton, a turned box, a
//! heightfield with nodata or a domain polygon, any other leaf — is a
//! [`TapeError::NoEncoding`] naming it, and
//! `karstic render --gpu` falls back to the CPU with that message. An instanced subtree
//! (one node with several parents) is emitted once per use: a tape is a tree.

use glam::Vec3;

use super::{Combine, HeightGrid, Profile, Shape, Tape, TapeBuilder, TapeError};
use crate::dem::HeightfieldField;
use crate::elevation::ElevationField;
use crate::field::skeleton::Project;
use crate::field::{Field, ISO, Node, NodeId, Primitive, Skeleton, Tree};
use crate::voxel::SField;

/// The GPU tape of a compiled tree, or the first node without an encoding.
pub fn tape_from_tree(tree: &Tree) -> Result<Tape, TapeError> {
    let mut b = TapeBuilder::new();
    emit(tree, &mut b, tree.root())?;
    b.finish()
}

impl Tape {
    /// [`tape_from_tree`].
    pub fn from_tree(tree: &Tree) -> Result<Tape, TapeError> {
        tape_from_tree(tree)
    }

    /// The same tape carrying the heightfield `ground` (its samples and parameters, see
    /// [`Tape::ground`]) for the materials to tell features from ground on the GPU.
    pub fn with_ground(mut self, ground: &HeightfieldField) -> Result<Tape, TapeError> {
        let grid = height_grid(ground)
            .map_err(|why| TapeError::Invalid(format!("the terrain of the materials: {why}")))?;
        // The materials read the DEM's elevation, without detail (as the CPU's do).
        let grid = HeightGrid {
            detail: None,
            ..grid
        };
        let (flags, q) = super::height::encode(
            &grid,
            ground.params().falloff,
            &mut self.heights,
            &mut self.noises,
        )?;
        self.ground = Some((flags, self.params.len() as u32));
        self.params.extend_from_slice(&q);
        Ok(self)
    }
}

/// The grid of a heightfield leaf, or why the tape cannot hold it.
fn height_grid(h: &HeightfieldField) -> Result<HeightGrid<'_>, &'static str> {
    let grid = h.heightfield();
    let cell = grid.cell();
    if h.params().domain.is_some() {
        return Err("a domain polygon is not encoded");
    }
    if h.inset().is_some() {
        return Err("an eroded amplification is not encoded");
    }
    if grid.nodata_count() > 0 {
        return Err("DEMs with nodata samples are not encoded");
    }
    if cell.x != cell.y {
        return Err("only square cells are encoded");
    }
    Ok(HeightGrid {
        origin: grid.origin(),
        cell: cell.x,
        nx: grid.nx(),
        ny: grid.ny(),
        z: grid.samples(),
        interpolation: h.params().interpolation,
        detail: h.detail(),
    })
}

/// How to name node `id` in messages: its user name when it has one.
fn describe(tree: &Tree, id: NodeId, kind: &str) -> String {
    match &tree.info(id).name {
        Some(n) => format!("the {kind} {n:?}"),
        None => format!("a {kind} (node #{id})"),
    }
}

fn no_encoding(tree: &Tree, id: NodeId, kind: &str, why: &str) -> TapeError {
    TapeError::NoEncoding {
        node: describe(tree, id, kind),
        why: why.into(),
    }
}

/// True for the nodes worth a guard of their own: S-field volumes and noisy primitives,
/// whose evaluation is long, and placed subtrees (a generated arch: one guard skips all of
/// it). On lavapipe, every lane of a SIMD group pays for a leaf any lane evaluates; a
/// guard lets rays away from the node jump over it.
fn costly(node: &Node) -> bool {
    let leaf = match node {
        Node::Primitive(p) => return p.noise().is_some(),
        Node::Affine { .. } => return true,
        Node::Leaf(f) => f.as_any(),
        _ => return false,
    };
    leaf.is_some_and(|a| {
        a.is::<SField>()
            || a.downcast_ref::<Primitive>()
                .is_some_and(|p| p.noise().is_some())
    })
}

/// Emits node `id`, leaving one entry on the builder's stack.
fn emit(tree: &Tree, b: &mut TapeBuilder, id: NodeId) -> Result<(), TapeError> {
    let node = &tree.nodes()[id as usize];
    let support = tree.info(id).support;
    if costly(node) && !support.is_empty() && support.size().is_finite() {
        // Every node is 0 outside its support box, so a guard may stand before it.
        // The tree's support is the one the guard checks (the builder's own estimate of
        // a primitive's may differ from it by a rounding).
        let g = b.guard_begin(support);
        emit_node(tree, b, id, node)?;
        b.assume_support(support)?;
        return b.guard_end(g);
    }
    emit_node(tree, b, id, node)?;
    b.assume_support(support)
}

/// Emits `node` (node `id`) without a guard of its own.
fn emit_node(tree: &Tree, b: &mut TapeBuilder, id: NodeId, node: &Node) -> Result<(), TapeError> {
    match node {
        Node::Constant(v) => b.constant(*v),
        Node::Primitive(p) => primitive(tree, b, id, p)?,
        Node::Leaf(f) => leaf(tree, b, id, f.as_ref())?,
        Node::Blend { children, bvh } => {
            if bvh.is_some() {
                let boxes: Vec<_> = children.iter().map(|&c| tree.info(c).support).collect();
                b.combine_bvh(Combine::Blend, &boxes, &mut |b, i| {
                    emit(tree, b, children[i])
                })?;
            } else {
                chain(tree, b, Combine::Blend, children)?;
            }
        }
        Node::Union(children) => chain(tree, b, Combine::Union, children)?,
        Node::Intersection(children) => chain(tree, b, Combine::Intersection, children)?,
        Node::Difference { base, carves } => {
            emit(tree, b, *base)?;
            for &c in carves.iter() {
                emit(tree, b, c)?;
                b.combine(Combine::Difference)?;
            }
        }
        Node::Replace { base, by, mix } => {
            emit(tree, b, *base)?;
            emit(tree, b, *by)?;
            b.replace(mix)?;
        }
        Node::Affine {
            child, to_child, ..
        } => {
            b.warp_begin_inverse(*to_child)?;
            emit(tree, b, *child)?;
            b.warp_end()?;
        }
        Node::Warp { child, warp } => {
            b.turbulence_begin(warp)?;
            emit(tree, b, *child)?;
            b.warp_end()?;
        }
        Node::Erode { .. } => {
            return Err(no_encoding(
                tree,
                id,
                "erosion node",
                "the tape has no encoding of geology trees",
            ));
        }
    }
    Ok(())
}

/// `c₀ ∘ c₁ ∘ …` as a chain of binary ops (an empty list is the constant 0).
fn chain(
    tree: &Tree,
    b: &mut TapeBuilder,
    how: Combine,
    children: &[NodeId],
) -> Result<(), TapeError> {
    let Some((&first, rest)) = children.split_first() else {
        b.constant(0.0);
        return Ok(());
    };
    emit(tree, b, first)?;
    for &c in rest {
        emit(tree, b, c)?;
        b.combine(how)?;
    }
    Ok(())
}

fn leaf(tree: &Tree, b: &mut TapeBuilder, id: NodeId, f: &dyn Field) -> Result<(), TapeError> {
    let any = f.as_any();
    if let Some(p) = any.and_then(|a| a.downcast_ref::<Primitive>()) {
        return primitive(tree, b, id, p);
    }
    if let Some(h) = any.and_then(|a| a.downcast_ref::<HeightfieldField>()) {
        return heightfield(tree, b, id, h);
    }
    if let Some(s) = any.and_then(|a| a.downcast_ref::<SField>()) {
        return b.sfield(s, &describe(tree, id, "S-field volume"));
    }
    if any.is_some_and(|a| a.is::<ElevationField>()) {
        return Err(no_encoding(
            tree,
            id,
            "elevation tree",
            "the tape encodes DEM rasters, not 2.5D elevation trees",
        ));
    }
    Err(no_encoding(
        tree,
        id,
        "leaf",
        "only skeletal primitives, heightfields and S-field volumes are encoded",
    ))
}

fn primitive(tree: &Tree, b: &mut TapeBuilder, id: NodeId, p: &Primitive) -> Result<(), TapeError> {
    let skeleton = p.skeleton();
    let kind = format!("{} primitive", skeleton.kind());
    let profile = Profile::Wyvill {
        radius: p.radius(),
        energy: p.energy(),
    };
    // The primitive on one convex shape, with its noise when it has one.
    let push = |b: &mut TapeBuilder, shape: Shape| match p.noise() {
        Some(n) => b.noisy_primitive(shape, p.radius(), p.energy(), n),
        None => {
            b.primitive(shape, profile);
            Ok(())
        }
    };
    let reach = p.radius() + p.noise().map_or(0.0, |n| n.amplitude);
    let shape = match skeleton {
        Skeleton::Point(s) => Shape::Point(s.center),
        Skeleton::Segment(s) => Shape::Segment(s.a(), s.b()),
        Skeleton::Sphere(s) => Shape::Sphere {
            center: s.inner().center,
            radius: s.radius(),
        },
        Skeleton::Capsule(s) => Shape::Capsule {
            a: s.inner().a(),
            b: s.inner().b(),
            radius: s.radius(),
        },
        Skeleton::Cone(c) => Shape::Cone {
            base: c.base(),
            axis: c.axis(),
            height: c.height(),
            radius: c.radius(),
        },
        Skeleton::Ellipsoid(e) => Shape::Ellipsoid {
            center: e.center(),
            radii: e.radii(),
        },
        Skeleton::Box(c) => axis_aligned_box(c).ok_or_else(|| {
            no_encoding(
                tree,
                id,
                &kind,
                "only boxes with a yaw that is a multiple of 90° are encoded",
            )
        })?,
        Skeleton::Polyline(chain) | Skeleton::Curve(chain) => {
            // E·g(minᵢ d̃ᵢ): the max of the segments' fields for E ≥ 0 (g decreasing), the
            // min for E < 0; with noise d̃ᵢ is each segment's anisotropic distance, and the
            // primitive's d̃ is their minimum too.
            let how = if p.energy() >= 0.0 {
                Combine::Union
            } else {
                Combine::Intersection
            };
            let shapes: Vec<Shape> = chain
                .segments()
                .iter()
                .map(|s| Shape::Segment(s.a(), s.b()))
                .collect();
            let boxes: Vec<_> = chain
                .segments()
                .iter()
                .map(|s| s.bounds().dilate(reach * 1.000_01))
                .collect();
            return b.combine_bvh(how, &boxes, &mut |b, i| push(b, shapes[i]));
        }
        other => {
            return Err(no_encoding(
                tree,
                id,
                &kind,
                &format!(
                    "the GPU evaluator knows point, segment, polyline, curve, sphere, capsule, box, cone and ellipsoid skeletons, not {}",
                    other.kind()
                ),
            ));
        }
    };
    push(b, shape)
}

/// The box as centre and half-size when its yaw is a multiple of 90° (it then fills its
/// bounding box); `None` for any other turn. The cuboid's fields are private, so this is
/// read off its bounds and checked through its projection: a turned rectangle does not
/// contain the corners of its bounding rectangle.
fn axis_aligned_box(c: &crate::field::skeleton::Cuboid) -> Option<Shape> {
    let bounds = c.bounds();
    let tol = 1e-5 * (bounds.max.abs().max_element() + bounds.min.abs().max_element()).max(1.0);
    let corners = [
        bounds.max,
        bounds.min,
        Vec3::new(bounds.min.x, bounds.max.y, bounds.max.z),
        Vec3::new(bounds.max.x, bounds.min.y, bounds.min.z),
    ];
    corners
        .iter()
        .all(|&k| c.distance(k) <= tol)
        .then(|| Shape::Box {
            center: bounds.center(),
            half: 0.5 * bounds.size(),
        })
}

fn heightfield(
    tree: &Tree,
    b: &mut TapeBuilder,
    id: NodeId,
    h: &HeightfieldField,
) -> Result<(), TapeError> {
    let r = h.params().falloff;
    let grid = height_grid(h).map_err(|why| no_encoding(tree, id, "heightfield", why))?;
    b.heightfield(&grid, r)?;
    // The leaf's prism field 2T·g(d_P/R), d_xy = R − clearance of the grid's rectangle.
    let rect = h.heightfield().extent();
    let dz = h.prism_z();
    b.primitive(
        Shape::Prism {
            min: (rect.min + r).extend(dz.lo),
            max: (rect.max - r).extend(dz.hi),
        },
        Profile::Wyvill {
            radius: r,
            energy: 2.0 * ISO,
        },
    );
    b.combine(Combine::Intersection)
}
