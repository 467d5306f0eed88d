//! Ray casting triangle meshes through an obvhs BVH: the faces the guided tracer follows
//! ([`super::guide`]: first faces, and whether a shadow ray enters the mesh's solid), and
//! the independent ground truth the tracer is checked against (the traced depth of a
//! tree against its Marching Cubes mesh).

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::bvh2::Bvh2;
use obvhs::ray::RayHit;
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use super::camera::{Camera, Ray};

/// A triangle mesh with a BVH over its faces.
pub struct MeshRaycaster {
    triangles: Vec<Triangle>,
    bvh: Bvh2,
}

impl MeshRaycaster {
    /// Builds the BVH over `faces` (indices into `positions`). Panics on an index out of
    /// range: meshes come from the mesher, not from users. obvhs's fastest build (a face a
    /// leaf, no reinsertion): the pictures' guides build BVHs of about a million faces
    /// each time, and the fastest build took 1.09 s of guides where the fast one took
    /// 1.31 s on the main view, which it traced as fast (`BENCHMARKS.md`).
    pub fn new(positions: &[Vec3], faces: &[[u32; 3]]) -> Self {
        let triangles: Vec<Triangle> = faces
            .iter()
            .map(|f| Triangle {
                v0: positions[f[0] as usize].into(),
                v1: positions[f[1] as usize].into(),
                v2: positions[f[2] as usize].into(),
            })
            .collect();
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(
            &triangles,
            obvhs::BvhBuildParams::fastest_build(),
            &mut Duration::default(),
        );
        MeshRaycaster { triangles, bvh }
    }

    /// Distance along `ray` to the nearest face, if any.
    pub fn first_hit(&self, ray: &Ray) -> Option<f32> {
        self.first_hit_within(ray, (0.0, f32::INFINITY))
    }

    /// Distance along `ray` to the nearest face with `t` in `[t0, t1]`, if any.
    pub fn first_hit_within(&self, ray: &Ray, span: (f32, f32)) -> Option<f32> {
        self.first_crossing_within(ray, span).map(|(t, _)| t)
    }

    /// The nearest face along `ray` with `t` in `[t0, t1]`, if any: its `t`, and whether
    /// the ray enters the solid there ([`enters`]) or leaves it.
    pub fn first_crossing_within(&self, ray: &Ray, span: (f32, f32)) -> Option<(f32, bool)> {
        let r = self.bvh_ray(ray, span)?;
        let mut hit = RayHit::none();
        let found = self
            .bvh
            .ray_traverse(r, &mut hit, |r, id| self.face(id).intersect(r));
        found.then(|| {
            (
                hit.t,
                enters(self.face(hit.primitive_id as usize), r.direction),
            )
        })
    }

    /// True when `ray` enters the solid through a face with `t` in `[t0, t1]` ([`enters`]).
    /// Faces the ray leaves the solid through are passed.
    pub fn enters_within(&self, ray: &Ray, span: (f32, f32)) -> bool {
        let Some(r) = self.bvh_ray(ray, span) else {
            return false;
        };
        !self.bvh.ray_traverse_miss(r, |r, id| {
            let tri = self.face(id);
            match enters(tri, r.direction) {
                true => tri.intersect(r),
                false => f32::INFINITY,
            }
        })
    }

    /// `ray` over `[t0, t1]` as obvhs asks it; `None` when there is nothing to cross (no
    /// face, or an empty span).
    fn bvh_ray(&self, ray: &Ray, (t0, t1): (f32, f32)) -> Option<obvhs::ray::Ray> {
        (!self.triangles.is_empty() && t0 <= t1)
            .then(|| obvhs::ray::Ray::new(Vec3A::from(ray.origin), Vec3A::from(ray.dir), t0, t1))
    }

    /// The face at BVH primitive slot `id`.
    fn face(&self, id: usize) -> &Triangle {
        &self.triangles[self.bvh.primitive_indices[id] as usize]
    }

    /// The depth image through `camera`: distance to the nearest face per pixel, `∞` on a
    /// miss (the same layout as [`crate::render::Frame::depth`]).
    pub fn depth(&self, camera: &Camera) -> Vec<f32> {
        let w = camera.width;
        (0..w * camera.height)
            .into_par_iter()
            .map(|k| {
                self.first_hit(&camera.pixel_ray(k % w, k / w))
                    .unwrap_or(f32::INFINITY)
            })
            .collect()
    }
}

/// True when a ray along `dir` crossing `tri` enters the solid: the face's outward side
/// (counter-clockwise, as the mesher winds faces) faces the ray.
fn enters(tri: &Triangle, dir: Vec3A) -> bool {
    (tri.v1 - tri.v0).cross(tri.v2 - tri.v0).dot(dir) < 0.0
}
