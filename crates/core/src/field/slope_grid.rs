//! The global Lipschitz bound of an n-ary blend, from a coarse grid of cells.
//!
//! `∇Σfᵢ(p)` is the sum of the gradients of the children whose supports contain `p`, so
//! `|∇Σfᵢ| ≤ max over cells C of Σ{λᵢ : supp fᵢ meets C}` for any partition into cells.
//! The cell of a point is `⌊(x − min)/size · dims⌋` per axis, a non-decreasing function
//! of `x` in floating point too, so a child whose support spans `[a, b]` can only be
//! non-zero in the cells from `cell(a)` to `cell(b)`: the bound is sound as computed.
//! Unlike "the heaviest group of supports overlapping one child's", it stays tight when
//! one large child (a ground slab) overlaps many small ones.

use glam::Vec3;

use super::bounds::Aabb;

/// Cells per child, and the most cells of one grid.
const CELLS_PER_CHILD: usize = 4;
const MAX_CELLS: usize = 1 << 20;

/// Supports beyond this are treated as unbounded (non-zero everywhere).
const HUGE: f32 = 1e15;

/// A sound Lipschitz bound of `Σ fᵢ` given each child's support and global bound.
pub fn blend_lipschitz(children: &[(Aabb, f32)]) -> f32 {
    let mut everywhere = 0.0f32;
    let mut bounded: Vec<(Aabb, f32)> = Vec::new();
    for &(b, l) in children {
        if b.is_empty() || l <= 0.0 {
            continue;
        }
        if b.min.abs().max_element() > HUGE || b.max.abs().max_element() > HUGE {
            everywhere += l;
        } else {
            bounded.push((b, l));
        }
    }
    if bounded.len() <= 1 {
        return everywhere + bounded.first().map_or(0.0, |c| c.1);
    }
    let hull = bounded.iter().fold(Aabb::EMPTY, |h, c| h.union(c.0));
    let dims = grid_dims(
        hull.size(),
        (bounded.len() * CELLS_PER_CHILD).min(MAX_CELLS),
    );
    let size = hull.size();
    let cell = |x: f32, a: usize| -> usize {
        if size[a] <= 0.0 {
            return 0;
        }
        let c = ((x - hull.min[a]) / size[a] * dims[a] as f32).floor();
        (c.max(0.0) as usize).min(dims[a] - 1)
    };
    let mut sums = vec![0.0f32; dims.iter().product()];
    for (b, l) in &bounded {
        let lo: [usize; 3] = std::array::from_fn(|a| cell(b.min[a], a));
        let hi: [usize; 3] = std::array::from_fn(|a| cell(b.max[a], a));
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                let row = dims[0] * (j + dims[1] * k);
                for s in &mut sums[row + lo[0]..=row + hi[0]] {
                    *s += l;
                }
            }
        }
    }
    everywhere + sums.iter().copied().fold(0.0, f32::max)
}

/// Cells along each axis: about `cells` in all, as cubic as the box allows.
pub(super) fn grid_dims(size: Vec3, cells: usize) -> [usize; 3] {
    let longest = size.max_element().max(f32::MIN_POSITIVE);
    // Flat axes get one cell; the others share the budget in proportion to their length.
    let s = size.max(Vec3::splat(longest * 1e-3));
    let side = (s.x * s.y * s.z / cells as f32).cbrt();
    let mut dims = [0; 3];
    for a in 0..3 {
        dims[a] = if size[a] <= 0.0 {
            1
        } else {
            ((s[a] / side).round() as usize).clamp(1, 4096)
        };
    }
    dims
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_under_small_balls_counts_once() {
        // A ground slab of slope 1 under 100 disjoint balls of slope 2: at most one ball
        // is non-zero at a point, so the bound is 1 + 2, not 1 + 200.
        let mut c = vec![(Aabb::new(Vec3::ZERO, Vec3::new(1000.0, 1000.0, 10.0)), 1.0)];
        for i in 0..10 {
            for j in 0..10 {
                let centre = Vec3::new(50.0 + 100.0 * i as f32, 50.0 + 100.0 * j as f32, 5.0);
                c.push((Aabb::around(centre, 4.0), 2.0));
            }
        }
        assert_eq!(blend_lipschitz(&c), 3.0);
    }

    #[test]
    fn overlapping_children_add_up() {
        let b = Aabb::around(Vec3::ZERO, 1.0);
        let c = [
            (b, 1.0),
            (b, 2.5),
            (Aabb::around(Vec3::splat(10.0), 1.0), 7.0),
        ];
        assert_eq!(blend_lipschitz(&c), 7.0);
        let everywhere = Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
        let c = [(b, 1.0), (b, 2.5), (everywhere, 0.5), (Aabb::EMPTY, 9.0)];
        assert_eq!(blend_lipschitz(&c), 4.0);
        // Touching boxes share their boundary: both count there.
        let c = [
            (Aabb::new(Vec3::ZERO, Vec3::ONE), 1.0),
            (Aabb::new(Vec3::X, Vec3::new(2.0, 1.0, 1.0)), 1.0),
        ];
        assert_eq!(blend_lipschitz(&c), 2.0);
    }
}
