//! Room made for features: balls around their curves and tubes, and a bucketed index
//! answering "is this point in some ball" (terrain samples giving way to a feature, a
//! level's guidance cleared where a feature first appears).

use glam::{UVec2, Vec2, Vec3};

use crate::field::Aabb;

/// Balls `(centre, radius)` bucketed on a horizontal grid of cells as large as the
/// largest radius.
#[derive(Clone, Debug, Default)]
pub struct Room {
    balls: Vec<(Vec3, f32)>,
    origin: Vec2,
    cell: f32,
    dims: [usize; 2],
    /// Per bucket, the balls reaching it (CSR: `starts[b]..starts[b + 1]` in `items`).
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl Room {
    /// The index of `balls`.
    pub fn new(balls: Vec<(Vec3, f32)>) -> Self {
        if balls.is_empty() {
            return Room::default();
        }
        let bounds = balls
            .iter()
            .fold(Aabb::EMPTY, |b, &(c, r)| b.union(Aabb::around(c, r)));
        let cell = balls.iter().map(|b| b.1).fold(1e-3, f32::max);
        let fp = bounds.footprint();
        let origin = fp.min;
        let n = ((fp.max - fp.min) / cell).ceil().as_uvec2() + 1;
        let dims = [n.x as usize, n.y as usize];
        let span = |c: Vec3, r: f32| {
            let lo = ((c.truncate() - r - origin) / cell)
                .floor()
                .max(Vec2::ZERO)
                .as_uvec2();
            let hi = ((c.truncate() + r - origin) / cell).floor().as_uvec2();
            (
                lo,
                hi.min(UVec2::new(dims[0] as u32 - 1, dims[1] as u32 - 1)),
            )
        };
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for (k, &(c, r)) in balls.iter().enumerate() {
                let (lo, hi) = span(c, r);
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        f(x as usize + dims[0] * y as usize, k as u32);
                    }
                }
            }
        };
        let mut starts = vec![0u32; dims[0] * dims[1] + 1];
        each(&mut |b, _| starts[b + 1] += 1);
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        let mut items = vec![0u32; starts[starts.len() - 1] as usize];
        let mut fill = starts.clone();
        each(&mut |b, k| {
            items[fill[b] as usize] = k;
            fill[b] += 1;
        });
        Room {
            balls,
            origin,
            cell,
            dims,
            starts,
            items,
        }
    }

    /// True when no ball is given.
    pub fn is_empty(&self) -> bool {
        self.balls.is_empty()
    }

    /// True when `p` lies in some ball.
    pub fn contains(&self, p: Vec3) -> bool {
        if self.balls.is_empty() {
            return false;
        }
        let g = ((p.truncate() - self.origin) / self.cell).floor();
        if g.x < 0.0 || g.y < 0.0 || g.x >= self.dims[0] as f32 || g.y >= self.dims[1] as f32 {
            return false;
        }
        let b = g.x as usize + self.dims[0] * g.y as usize;
        self.items[self.starts[b] as usize..self.starts[b + 1] as usize]
            .iter()
            .any(|&k| {
                let (c, r) = self.balls[k as usize];
                c.distance_squared(p) < r * r
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_exactly_the_points_in_some_ball() {
        let balls = vec![
            (Vec3::new(0.0, 0.0, 0.0), 2.0),
            (Vec3::new(10.0, 3.0, 5.0), 0.5),
            (Vec3::new(-7.0, 9.0, -2.0), 4.0),
        ];
        let room = Room::new(balls.clone());
        for i in 0..4000 {
            let f = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
            let p = Vec3::new(-12.0 + 24.0 * f(1), -4.0 + 16.0 * f(2), -7.0 + 14.0 * f(3));
            let want = balls.iter().any(|&(c, r)| c.distance(p) < r);
            assert_eq!(room.contains(p), want, "{p}");
        }
        assert!(!Room::default().contains(Vec3::ZERO));
    }
}
