//! Grid evaluation of the tree, brick by brick.
//!
//! A block of grid points is cut into [`BRICK`]³ bricks. Each brick is evaluated node by
//! node over all its points at once: a node whose support misses the brick is 0 there, a
//! blend visits (through its BVH) only the children whose supports meet the brick, a
//! union, intersection or carve drops the children its interval bounds show cannot win,
//! and a primitive child of a blend adds its values only over the sub-box of points inside
//! its support, with a vectorised loop for the round kernels (point, sphere) and nothing
//! at all where its interval over that sub-box is constant. Nothing is rebuilt per brick
//! and the scratch buffers are reused, so a brick allocates nothing.

use std::ops::Range;

use glam::Vec3;

use super::bounds::{Aabb, Interval};
use super::contract::Field;
use super::falloff::ISO;
use super::node::{Node, NodeId};
use super::primitive::{Primitive, Round};
use super::tree::Tree;

/// Side of the cubic bricks the grid evaluator works on.
pub const BRICK: usize = 8;

/// Points in a brick.
const BRICK_LEN: usize = BRICK * BRICK * BRICK;

/// Below this many points in its support, a primitive is evaluated without first checking
/// whether its interval there is constant.
const INTERVAL_MIN_POINTS: usize = 64;

/// A brick of grid points: point `(i, j, k)` (`i < dims[0]`, …, `i` fastest) is
/// `origin + (first + (i, j, k))·step`, computed exactly as [`Lattice::point`] does.
#[derive(Clone, Copy)]
struct Lattice {
    origin: Vec3,
    step: Vec3,
    first: [usize; 3],
    dims: [usize; 3],
}

impl Lattice {
    #[inline]
    fn coord(&self, axis: usize, i: usize) -> f32 {
        self.origin[axis] + (self.first[axis] + i) as f32 * self.step[axis]
    }

    #[inline]
    fn point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        Vec3::new(self.coord(0, i), self.coord(1, j), self.coord(2, k))
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    fn bounds(&self) -> Aabb {
        let [nx, ny, nz] = self.dims;
        Aabb::new(self.point(0, 0, 0), self.point(nx - 1, ny - 1, nz - 1))
    }

    /// The indices along `axis` whose coordinates lie in `[lo, hi]`: exactly those for a
    /// positive step, all of them otherwise.
    fn range(&self, axis: usize, lo: f32, hi: f32) -> Range<usize> {
        let n = self.dims[axis];
        let s = self.step[axis];
        if !(s > 0.0) {
            return 0..n;
        }
        let at = |x: f32| (x - self.origin[axis]) / s - self.first[axis] as f32;
        let clamp = |x: f32| x.clamp(0.0, n as f32) as usize;
        let (mut a, mut b) = (clamp(at(lo).ceil()), clamp(at(hi).floor() + 1.0));
        while a > 0 && self.coord(axis, a - 1) >= lo {
            a -= 1;
        }
        while a < n && self.coord(axis, a) < lo {
            a += 1;
        }
        while b < n && self.coord(axis, b) <= hi {
            b += 1;
        }
        while b > a && self.coord(axis, b - 1) > hi {
            b -= 1;
        }
        a..b.max(a)
    }

    /// The index ranges of the points inside `b`.
    fn ranges(&self, b: &Aabb) -> [Range<usize>; 3] {
        std::array::from_fn(|a| self.range(a, b.min[a], b.max[a]))
    }
}

/// The points a node is evaluated at: the brick's lattice, or the images of its points
/// under the warps and transforms above the node.
#[derive(Clone, Copy)]
enum Points<'a> {
    Lattice(Lattice),
    List(&'a [Vec3]),
}

impl Points<'_> {
    fn for_each(&self, mut f: impl FnMut(usize, Vec3)) {
        match self {
            Points::Lattice(l) => {
                let [nx, ny, nz] = l.dims;
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            f(i + nx * (j + ny * k), l.point(i, j, k));
                        }
                    }
                }
            }
            Points::List(ps) => ps.iter().enumerate().for_each(|(i, &p)| f(i, p)),
        }
    }
}

/// Reusable buffers, taken and given back around each nested evaluation.
#[derive(Default)]
struct Scratch {
    values: Vec<Vec<f32>>,
    points: Vec<Vec<Vec3>>,
    intervals: Vec<Vec<Interval>>,
}

impl Scratch {
    fn values(&mut self, n: usize) -> Vec<f32> {
        let mut v = self.values.pop().unwrap_or_default();
        v.clear();
        v.resize(n, 0.0);
        v
    }
}

impl Tree {
    /// Values of node `id` on a block of grid points (see [`Field::eval_block`]),
    /// evaluated per [`BRICK`]³ brick. The result does not depend on how the caller splits
    /// a grid into blocks along z, nor on threads.
    pub fn eval_block_at(
        &self,
        id: NodeId,
        origin: Vec3,
        step: Vec3,
        dims: [usize; 3],
        out: &mut [f32],
    ) {
        let [nx, ny, nz] = dims;
        assert!(out.len() >= nx * ny * nz, "eval_block: output too small");
        let mut scratch = Scratch::default();
        let mut values = [0.0f32; BRICK_LEN];
        for k0 in (0..nz).step_by(BRICK) {
            for j0 in (0..ny).step_by(BRICK) {
                for i0 in (0..nx).step_by(BRICK) {
                    let l = Lattice {
                        origin,
                        step,
                        first: [i0, j0, k0],
                        dims: [
                            (nx - i0).min(BRICK),
                            (ny - j0).min(BRICK),
                            (nz - k0).min(BRICK),
                        ],
                    };
                    let values = &mut values[..l.len()];
                    self.block(id, Points::Lattice(l), &l.bounds(), values, &mut scratch);
                    let [bx, by, bz] = l.dims;
                    for k in 0..bz {
                        for j in 0..by {
                            let at = i0 + nx * (j0 + j + ny * (k0 + k));
                            let from = bx * (j + by * k);
                            out[at..at + bx].copy_from_slice(&values[from..from + bx]);
                        }
                    }
                }
            }
        }
    }

    /// `out[i] = f(pᵢ)` for node `id` and the points `pts`, which lie in `bounds`.
    fn block(&self, id: NodeId, pts: Points, bounds: &Aabb, out: &mut [f32], s: &mut Scratch) {
        let support = &self.supports[id as usize];
        if !support.overlaps(bounds) {
            out.fill(0.0);
            return;
        }
        match &self.nodes[id as usize] {
            Node::Constant(v) => out.fill(*v),
            Node::Primitive(p) => {
                out.fill(0.0);
                add_primitive(p, support, pts, out);
            }
            Node::Leaf(f) => leaf(&**f, support, pts, bounds, out),
            Node::Blend { children, bvh } => {
                out.fill(0.0);
                self.blend_children_in(children, bvh, bounds, |c| match &self.nodes[c as usize] {
                    Node::Primitive(p) => add_primitive(p, &self.supports[c as usize], pts, out),
                    _ => {
                        let mut v = s.values(out.len());
                        self.block(c, pts, bounds, &mut v, s);
                        out.iter_mut().zip(&v).for_each(|(o, v)| *o += v);
                        s.values.push(v);
                    }
                });
            }
            Node::Union(children) | Node::Intersection(children) => {
                let union = matches!(self.nodes[id as usize], Node::Union(_));
                let mut ivs = s.intervals.pop().unwrap_or_default();
                ivs.clear();
                ivs.extend(children.iter().map(|&c| self.interval_at(c, bounds)));
                // A child that is below (above) another one throughout cannot be the max
                // (min): it is not evaluated.
                let bar = if union {
                    ivs.iter().map(|i| i.lo).fold(f32::NEG_INFINITY, f32::max)
                } else {
                    ivs.iter().map(|i| i.hi).fold(f32::INFINITY, f32::min)
                };
                let mut first = true;
                for (&c, iv) in children.iter().zip(&ivs) {
                    if (union && iv.hi < bar) || (!union && iv.lo > bar) {
                        continue;
                    }
                    if first {
                        self.block(c, pts, bounds, out, s);
                        first = false;
                        continue;
                    }
                    let mut v = s.values(out.len());
                    self.block(c, pts, bounds, &mut v, s);
                    for (o, v) in out.iter_mut().zip(&v) {
                        *o = if union { o.max(*v) } else { o.min(*v) };
                    }
                    s.values.push(v);
                }
                s.intervals.push(ivs);
            }
            Node::Difference { base, carves } => {
                self.block(*base, pts, bounds, out, s);
                if carves.is_empty() {
                    return;
                }
                let bi = self.interval_at(*base, bounds);
                for &c in carves.iter() {
                    // The carve wins nowhere when 2T − f_c ≥ f_base throughout.
                    if 2.0 * ISO - self.interval_at(c, bounds).hi >= bi.hi {
                        continue;
                    }
                    let mut v = s.values(out.len());
                    self.block(c, pts, bounds, &mut v, s);
                    for (o, v) in out.iter_mut().zip(&v) {
                        *o = o.min(2.0 * ISO - v);
                    }
                    s.values.push(v);
                }
            }
            Node::Replace { base, by, mix } => {
                let w = mix.interval(bounds);
                if w.lo >= 1.0 {
                    return self.block(*by, pts, bounds, out, s);
                }
                self.block(*base, pts, bounds, out, s);
                if w.hi <= 0.0 {
                    return;
                }
                let mut v = s.values(out.len());
                self.block(*by, pts, bounds, &mut v, s);
                pts.for_each(|i, p| out[i] += mix.weight(p) * (v[i] - out[i]));
                s.values.push(v);
            }
            Node::Affine {
                child, to_child, ..
            } => self.mapped(*child, pts, out, s, |p| to_child.transform_point3(p)),
            Node::Warp { child, warp } => self.mapped(*child, pts, out, s, |p| warp.apply(p)),
            Node::Erode { child, erosion } => {
                self.block(*child, pts, bounds, out, s);
                if erosion.interval(bounds).hi > 0.0 {
                    pts.for_each(|i, p| out[i] -= erosion.amount(p));
                }
            }
        }
    }

    /// `out[i] = f_child(map(pᵢ))`.
    fn mapped(
        &self,
        child: NodeId,
        pts: Points,
        out: &mut [f32],
        s: &mut Scratch,
        map: impl Fn(Vec3) -> Vec3,
    ) {
        let mut q = s.points.pop().unwrap_or_default();
        q.clear();
        q.resize(out.len(), Vec3::ZERO);
        pts.for_each(|i, p| q[i] = map(p));
        let bounds = Aabb::from_points(q.iter().copied());
        self.block(child, Points::List(&q), &bounds, out, s);
        s.points.push(q);
    }
}

/// `out[i] = f(pᵢ)` inside `support`, 0 outside, for a leaf that is not a primitive; on a
/// lattice through the leaf's own [`Field::eval_block`].
fn leaf(f: &dyn Field, support: &Aabb, pts: Points, bounds: &Aabb, out: &mut [f32]) {
    match pts {
        Points::Lattice(l) => {
            f.eval_block(l.point(0, 0, 0), l.step, l.dims, out);
            if !support.contains_box(bounds) {
                pts.for_each(|i, p| {
                    if !support.contains(p) {
                        out[i] = 0.0;
                    }
                });
            }
        }
        Points::List(_) => pts.for_each(|i, p| {
            out[i] = if support.contains(p) { f.value(p) } else { 0.0 };
        }),
    }
}

/// Adds `f(pᵢ)` to `out[i]` for the points inside `support`.
fn add_primitive(p: &Primitive, support: &Aabb, pts: Points, out: &mut [f32]) {
    let l = match pts {
        Points::Lattice(l) => l,
        Points::List(ps) => {
            for (o, &q) in out.iter_mut().zip(ps) {
                if support.contains(q) {
                    *o += p.value(q);
                }
            }
            return;
        }
    };
    let [ir, jr, kr] = l.ranges(support);
    let count = ir.len() * jr.len() * kr.len();
    if count == 0 {
        return;
    }
    let [nx, ny, _] = l.dims;
    if count >= INTERVAL_MIN_POINTS {
        let sub = Aabb::new(
            l.point(ir.start, jr.start, kr.start),
            l.point(ir.end - 1, jr.end - 1, kr.end - 1),
        );
        let iv = p.interval(&sub);
        if iv.lo == iv.hi {
            if iv.lo != 0.0 {
                for k in kr {
                    for j in jr.clone() {
                        let row = nx * (j + ny * k);
                        out[row + ir.start..row + ir.end]
                            .iter_mut()
                            .for_each(|o| *o += iv.lo);
                    }
                }
            }
            return;
        }
    }
    let mut xs = [0.0f32; BRICK];
    for (i, x) in ir.clone().zip(&mut xs) {
        *x = l.coord(0, i);
    }
    let xs = &xs[..ir.len()];
    let round = Round::of(p);
    for k in kr {
        let z = l.coord(2, k);
        for j in jr.clone() {
            let y = l.coord(1, j);
            let row = nx * (j + ny * k);
            match &round {
                Some(r) => {
                    let Some((x0, x1)) = r.row_extent(y, z) else {
                        continue;
                    };
                    let near = l.range(0, x0, x1);
                    let (a, b) = (near.start.max(ir.start), near.end.min(ir.end));
                    if a < b {
                        let at = a - ir.start;
                        r.add_row(&xs[at..at + b - a], y, z, &mut out[row + a..row + b]);
                    }
                }
                None => {
                    for (i, &x) in ir.clone().zip(xs) {
                        out[row + i] += p.value(Vec3::new(x, y, z));
                    }
                }
            }
        }
    }
}
