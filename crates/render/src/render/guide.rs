//! Empty-space skipping for pictures of a meshed region: the region's Marching Cubes mesh
//! tells the tracer where, inside the region, the surface can be.
//!
//! The job meshes its region before rendering it. The mesh's faces lie on the surface the
//! mesher's samples saw, within a cell of it. Inside the region a ray therefore:
//!
//! * walks a grid of the cells the faces touch, dilated by a cell (Amanatides & Woo
//!   1987): elsewhere in the region it is in the air, and the march runs only along the
//!   runs of marked cells;
//! * asks a BVH of the faces for the first face it meets, and skips the runs that end a
//!   cell before it: the mesher saw no surface there. The field is sampled a cell before
//!   the face (solid there: the surface came earlier, and the march takes over from the
//!   run's start), then at the face, which tells on which side of it the surface lies;
//!   there it is sought a quarter of a cell away, then a cell away. When that brackets
//!   the surface, false position locates it (a few evaluations where the march near a
//!   surface takes dozens), else the march takes over from a cell before the face.
//! * A shadow ray does not march: it is occluded when it enters the mesh's solid through
//!   a face turned towards it, or when it starts inside that solid and is still inside
//!   two cells on. A face it leaves through within those two cells is the mesh's copy of
//!   the surface it leaves, which lies within a cell of the field's, above or below it;
//!   still inside beyond them, the ray is going through rock (from the foot of a ledge's
//!   riser, say). (Marching the first two cells in the field instead, as this did
//!   before, took a third of the main job's view for the same picture.)
//!
//! What the tracer finds is the field's own surface (its normals, materials and occlusion
//! are the field's), at the field's tolerance; what it gives up is what the mesh gives
//! up: solid that the mesher's samples miss (thinner than a cell) is not drawn inside the
//! region, as it is not in the mesh the job writes. Rays that meet no face still march the
//! marked runs they cross, so a ray slipping between two faces cannot see through the
//! ground. Outside the region rays are traced as before.

use glam::{IVec3, UVec3, Vec3};

use super::camera::Ray;
use super::raycast::MeshRaycaster;
use crate::field::Aabb;
use crate::io::{IoError, check_budget};
use crate::mesh::Mesh;

const DILATE: i32 = 1;

/// Where a meshed region's surface can be: the cells of a regular grid its faces touch
/// (dilated), and a BVH of the faces.
pub struct Guide {
    /// The mesh's faces.
    faces: MeshRaycaster,
    /// Corner of cell `(0, 0, 0)`.
    origin: Vec3,
    /// Side of a cell, metres.
    cell: f32,
    /// Cells per axis.
    dims: UVec3,
    /// One bit a cell, x fastest.
    bits: Vec<u64>,
}

impl std::fmt::Debug for Guide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Guide")
            .field("bounds", &self.bounds())
            .field("cell", &self.cell)
            .finish_non_exhaustive()
    }
}

impl Guide {
    /// The guide of `mesh` over `region`: the cells of side `cell` its faces touch, each
    /// face's box dilated by a cell (the surface between a face's vertices strays from the
    /// face by less than that), and the BVH of its faces. Refuses a grid whose bits exceed
    /// `budget` bytes.
    pub fn from_mesh(mesh: &Mesh, region: &Aabb, cell: f32, budget: u64) -> Result<Self, IoError> {
        let origin = region.min;
        let dims = ((region.max - region.min) / cell)
            .ceil()
            .max(Vec3::ONE)
            .as_uvec3();
        let count = dims.x as u64 * dims.y as u64 * dims.z as u64;
        check_budget(
            format!(
                "an occupancy grid of {} × {} × {} cells",
                dims.x, dims.y, dims.z
            ),
            count.div_ceil(64) * 8,
            budget,
        )?;
        let positions: Vec<Vec3> = mesh.positions.iter().map(|p| Vec3::from(*p)).collect();
        let mut guide = Guide {
            faces: MeshRaycaster::new(&positions, &mesh.triangles),
            origin,
            cell,
            dims,
            bits: vec![0; count.div_ceil(64) as usize],
        };
        let top = dims.as_ivec3() - IVec3::ONE;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let lo = guide.cell_of(a.min(b).min(c)) - IVec3::splat(DILATE);
            let hi = guide.cell_of(a.max(b).max(c)) + IVec3::splat(DILATE);
            let (lo, hi) = (lo.clamp(IVec3::ZERO, top), hi.clamp(IVec3::ZERO, top));
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let k = guide.index(IVec3::new(x, y, z));
                        guide.bits[k / 64] |= 1 << (k % 64);
                    }
                }
            }
        }
        Ok(guide)
    }

    /// The box the grid covers.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.origin, self.origin + self.dims.as_vec3() * self.cell)
    }

    /// Side of a cell, metres.
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// True when the cell holding `p` (inside the grid) is marked.
    pub fn marked(&self, p: Vec3) -> bool {
        let c = self.cell_of(p);
        let inside = c.cmpge(IVec3::ZERO).all() && c.cmplt(self.dims.as_ivec3()).all();
        inside && self.is_set(c)
    }

    /// The first face along `ray` with `t` in `span`.
    pub fn first_face(&self, ray: &Ray, span: (f32, f32)) -> Option<f32> {
        self.faces.first_hit_within(ray, span)
    }

    /// True when the mesh hides the sun from a shadow ray over `span`: the ray enters the
    /// mesh's solid through a face turned towards it, or it starts inside that solid
    /// (under the mesh's copy of the surface it leaves, which lies within a cell of the
    /// field's) and is still inside `reach` further on, going through rock, not
    /// leaving a surface ([`MeshRaycaster::first_crossing_within`]).
    pub fn hides(&self, ray: &Ray, span: (f32, f32), reach: f32) -> bool {
        match self.faces.first_crossing_within(ray, span) {
            None => false,
            Some((_, true)) => true,
            Some((t, false)) => t - span.0 > reach || self.faces.enters_within(ray, (t, span.1)),
        }
    }

    /// The cell holding `p` (unclamped).
    fn cell_of(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) / self.cell).floor().as_ivec3()
    }

    fn index(&self, c: IVec3) -> usize {
        (c.x as u32 + self.dims.x * (c.y as u32 + self.dims.y * c.z as u32)) as usize
    }

    fn is_set(&self, c: IVec3) -> bool {
        let k = self.index(c);
        self.bits[k / 64] >> (k % 64) & 1 == 1
    }

    /// The spans `[t0, t1]` of `ray` within `span` that cross marked cells, in order (a
    /// run of adjacent marked cells is one span); `span` must lie in [`Self::bounds`]
    /// (e.g. the ray clipped to it).
    pub fn runs(&self, ray: &Ray, span: (f32, f32)) -> Runs<'_> {
        // Start in the cell of a point a hair inside the span, clamped to the grid.
        let top = self.dims.as_ivec3() - IVec3::ONE;
        let start = ray.at(span.0 + 1e-4 * (span.1 - span.0));
        let cell = self.cell_of(start).clamp(IVec3::ZERO, top);
        let step = ray.dir.signum().as_ivec3();
        // Parameter of the next cell boundary on each axis, and between boundaries.
        let next_face = self.origin + (cell + step.max(IVec3::ZERO)).as_vec3() * self.cell;
        let inv = ray.dir.recip();
        let t_next = finite_or_infinite((next_face - ray.origin) * inv);
        let t_delta = finite_or_infinite(self.cell * inv.abs());
        Runs {
            guide: self,
            cell,
            step,
            t_next,
            t_delta,
            t: span.0,
            end: span.1,
        }
    }
}

/// `v` with its non-finite lanes set to `∞` (a ray parallel to an axis never crosses its
/// boundaries).
fn finite_or_infinite(v: Vec3) -> Vec3 {
    Vec3::select(v.is_finite_mask(), v, Vec3::INFINITY)
}

/// The runs of a ray through an [`Guide`]'s marked cells ([`Guide::runs`]).
pub struct Runs<'a> {
    guide: &'a Guide,
    cell: IVec3,
    step: IVec3,
    t_next: Vec3,
    t_delta: Vec3,
    /// Where the current cell was entered.
    t: f32,
    end: f32,
}

impl Runs<'_> {
    /// Moves to the next cell along the ray; false when the ray leaves the grid or the
    /// span.
    fn advance(&mut self) -> bool {
        let axis = if self.t_next.x <= self.t_next.y && self.t_next.x <= self.t_next.z {
            0
        } else if self.t_next.y <= self.t_next.z {
            1
        } else {
            2
        };
        self.t = self.t_next[axis];
        self.t_next[axis] += self.t_delta[axis];
        self.cell[axis] += self.step[axis];
        let c = self.cell[axis];
        self.t < self.end && c >= 0 && c < self.guide.dims.as_ivec3()[axis]
    }
}

impl Iterator for Runs<'_> {
    type Item = (f32, f32);

    fn next(&mut self) -> Option<(f32, f32)> {
        if self.t >= self.end {
            return None;
        }
        // Skip the air.
        while !self.guide.is_set(self.cell) {
            if !self.advance() {
                self.t = self.end;
                return None;
            }
        }
        let start = self.t;
        // Take the marked cells that follow.
        loop {
            if !self.advance() {
                let end = self.end;
                self.t = end;
                return Some((start, end));
            }
            if !self.guide.is_set(self.cell) {
                return Some((start, self.t));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(triangles: &[[Vec3; 3]]) -> Mesh {
        Mesh {
            positions: triangles.iter().flatten().map(|p| p.to_array()).collect(),
            normals: vec![[0.0, 0.0, 1.0]; 3 * triangles.len()],
            triangles: (0..triangles.len() as u32)
                .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
                .collect(),
            attributes: Vec::new(),
        }
    }

    #[test]
    fn runs_cover_the_dilated_faces_and_nothing_else() {
        // A small triangle in the middle of a 10 m box of 1 m cells.
        let region = Aabb::new(Vec3::ZERO, Vec3::splat(10.0));
        let tri = [
            Vec3::new(4.2, 4.2, 5.5),
            Vec3::new(4.8, 4.2, 5.5),
            Vec3::new(4.2, 4.8, 5.5),
        ];
        let occ = Guide::from_mesh(&mesh(&[tri]), &region, 1.0, 1 << 20).unwrap();
        let centres = (0..1000)
            .map(|k| Vec3::new((k % 10) as f32, (k / 10 % 10) as f32, (k / 100) as f32) + 0.5);
        let marked = centres.filter(|&c| occ.marked(c)).count();
        assert_eq!(marked, 27, "the triangle's 3 × 3 × 3 cells");
        assert!(occ.marked(Vec3::new(3.5, 5.9, 6.9)));
        assert!(!occ.marked(Vec3::new(2.9, 4.5, 5.5)));
        // Rays along and across the axes, and a diagonal: each run is exactly the
        // marked cells the ray crosses (checked by dense sampling).
        let rays = [
            Ray {
                origin: Vec3::new(-1.0, 4.5, 5.5),
                dir: Vec3::X,
            },
            Ray {
                origin: Vec3::new(4.5, 11.0, 5.2),
                dir: -Vec3::Y,
            },
            Ray {
                origin: Vec3::new(0.1, 0.3, 0.2),
                dir: Vec3::new(1.0, 1.05, 1.2).normalize(),
            },
            Ray {
                origin: Vec3::new(0.5, 0.5, 9.0),
                dir: Vec3::new(1.0, 1.0, -0.9).normalize(),
            },
            Ray {
                origin: Vec3::new(3.0, 3.0, 20.0),
                dir: -Vec3::Z,
            },
        ];
        for ray in rays {
            let span = ray.clip(&occ.bounds()).unwrap();
            let runs: Vec<(f32, f32)> = occ.runs(&ray, span).collect();
            let n = 20_000;
            for k in 0..n {
                let t = span.0 + (span.1 - span.0) * (k as f32 + 0.5) / n as f32;
                // Points within a hair of a run's end may round to either cell.
                if runs
                    .iter()
                    .any(|r| (t - r.0).abs() < 1e-3 || (t - r.1).abs() < 1e-3)
                {
                    continue;
                }
                let inside = runs.iter().any(|r| r.0 <= t && t <= r.1);
                assert_eq!(inside, occ.marked(ray.at(t)), "{ray:?} at {t}: {runs:?}");
            }
        }
        // A ray that misses the marked cells has no run; one through them has one.
        let miss = Ray {
            origin: Vec3::new(0.5, 0.5, -1.0),
            dir: Vec3::Z,
        };
        assert_eq!(
            occ.runs(&miss, miss.clip(&occ.bounds()).unwrap()).count(),
            0
        );
        let hit = Ray {
            origin: Vec3::new(4.5, 4.5, -1.0),
            dir: Vec3::Z,
        };
        let runs: Vec<_> = occ.runs(&hit, hit.clip(&occ.bounds()).unwrap()).collect();
        assert_eq!(runs.len(), 1);
        assert!(
            (runs[0].0 - 5.0).abs() < 1e-4 && (runs[0].1 - 8.0).abs() < 1e-4,
            "{runs:?}"
        );
    }

    #[test]
    fn shadow_rays_are_hidden_by_faces_they_enter_through_or_by_rock() {
        // A floor at z = 1 and, 20 m along x, a ledge whose underside is at z = 4 and
        // top at z = 6, wound counter-clockwise seen from outside (the air); at x = 40–45,
        // y = 30–50, a wall 19 m high standing on the floor.
        let quad = |[a, b, c, d]: [Vec3; 4]| [[a, b, c], [a, c, d]];
        let flat = |z: f32, x0: f32, x1: f32, up: bool| {
            let (a, b) = (Vec3::new(x0, -50.0, z), Vec3::new(x1, -50.0, z));
            let (c, d) = (Vec3::new(x1, 50.0, z), Vec3::new(x0, 50.0, z));
            quad(if up { [a, b, c, d] } else { [a, d, c, b] })
        };
        let v = Vec3::new;
        let wall = [
            quad([
                v(40., 30., 1.),
                v(40., 30., 20.),
                v(40., 50., 20.),
                v(40., 50., 1.),
            ]),
            quad([
                v(45., 30., 1.),
                v(45., 50., 1.),
                v(45., 50., 20.),
                v(45., 30., 20.),
            ]),
            quad([
                v(40., 30., 20.),
                v(45., 30., 20.),
                v(45., 50., 20.),
                v(40., 50., 20.),
            ]),
        ]
        .concat();
        let faces: Vec<[Vec3; 3]> = [
            flat(1.0, -50.0, 40.0, true),
            flat(4.0, 20.0, 30.0, false),
            flat(6.0, 20.0, 30.0, true),
        ]
        .concat()
        .into_iter()
        .chain(wall)
        .collect();
        let region = Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0));
        let g = Guide::from_mesh(&mesh(&faces), &region, 1.0, 1 << 20).unwrap();
        let hidden = |origin: Vec3, to: Vec3| {
            let ray = Ray {
                origin,
                dir: (to - origin).normalize(),
            };
            g.hides(&ray, ray.clip(&g.bounds()).unwrap(), 2.0)
        };
        // Starting a hair under the floor's face (the mesh of the surface it leaves),
        // a ray climbing away passes out through it: lit.
        assert!(!hidden(
            Vec3::new(0.0, 0.0, 0.98),
            Vec3::new(-10.0, 0.0, 10.0)
        ));
        // The same ray towards the ledge enters its underside: in shadow.
        assert!(hidden(Vec3::new(0.0, 0.0, 0.98), Vec3::new(30.0, 0.0, 4.5)));
        // Over the ledge, or from inside it going up out of it, nothing is entered.
        assert!(!hidden(
            Vec3::new(0.0, 0.0, 1.02),
            Vec3::new(25.0, 0.0, 9.0)
        ));
        assert!(!hidden(
            Vec3::new(25.0, 0.0, 5.0),
            Vec3::new(26.0, 0.0, 40.0)
        ));
        // From under the ledge straight up: its underside.
        assert!(hidden(
            Vec3::new(25.0, 0.0, 1.02),
            Vec3::new(25.0, 0.0, 40.0)
        ));
        // From the foot of the wall, a hair inside the mesh's solid, into the rock: no
        // face is entered, but the ray leaves the solid only 9 m on, beyond the reach.
        assert!(hidden(
            Vec3::new(40.02, 40.0, 0.98),
            Vec3::new(60.0, 40.0, 30.0)
        ));
    }

    #[test]
    fn a_grid_over_the_budget_is_refused() {
        let region = Aabb::new(Vec3::ZERO, Vec3::splat(1000.0));
        let e = Guide::from_mesh(&mesh(&[]), &region, 0.1, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("occupancy grid"), "{e}");
    }
}
