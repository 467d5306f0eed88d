//! Sampling a field on a dense grid (`karstic sample`) and the JSON sidecar that tells
//! other tools where the samples are.

use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::MeshError;
use crate::field::{Aabb, Field, Grid, ISO, eval_grid};
use crate::io::{check_budget, content_hash};

/// `dims` samples spanning `b` corner to corner. An axis of one sample takes the box's
/// middle on that axis, where the box may be flat: a section on a plane is
/// `--box X0 Y Z0 X1 Y Z1 --res NX 1 NZ`.
pub fn grid_spanning(b: &Aabb, dims: [usize; 3]) -> Result<Grid, MeshError> {
    if dims.contains(&0) {
        return Err(MeshError::GridShape(format!(
            "resolution {}×{}×{}: each axis needs at least 1 sample",
            dims[0], dims[1], dims[2]
        )));
    }
    let size = b.size();
    let spans = (0..3).all(|a| dims[a] == 1 || size[a] > 0.0);
    if !(b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all() && spans) {
        return Err(MeshError::GridShape(format!(
            "box {} .. {}: expected a finite box with a positive size on every axis of more \
             than one sample",
            b.min, b.max
        )));
    }
    let (mut origin, mut step) = (b.min, Vec3::ZERO);
    for a in 0..3 {
        match dims[a] {
            1 => origin[a] = 0.5 * (b.min[a] + b.max[a]),
            n => step[a] = size[a] / (n - 1) as f32,
        }
    }
    Ok(Grid { origin, step, dims })
}

/// The values of `field` on `grid` ([`eval_grid`]: x fastest, then y, then z), refused
/// before anything is allocated when they would take more than `budget` bytes.
/// `progress` advances once per slab ([`crate::field::slab_count`]).
pub fn sample_grid(
    field: &dyn Field,
    grid: &Grid,
    budget: u64,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Vec<f32>, MeshError> {
    let [nx, ny, nz] = grid.dims;
    check_budget(format!("a {nx}×{ny}×{nz} grid"), grid.bytes(), budget)?;
    Ok(eval_grid(field, grid, progress))
}

/// The JSON sidecar of a sampled `.npy` grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sidecar {
    /// NumPy shape `[nz, ny, nx]`.
    pub shape: [usize; 3],
    /// Position of sample `[0, 0, 0]` (x, y, z; metres, Z up).
    pub origin: [f32; 3],
    /// Distance between samples along x, y, z.
    pub spacing: [f32; 3],
    /// The surface is `value = iso`, solid where `value > iso`.
    pub iso: f32,
    /// Human-readable index convention.
    pub layout: String,
    /// Content hash of the grid's values (16 hex digits), so that a grid and a sidecar
    /// from different runs (one cut short between its two files) are told apart.
    /// Sidecars written before it have none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<String>,
}

impl Sidecar {
    /// The sidecar of `values` sampled on `spec`.
    pub fn new(spec: &Grid, values: &[f32]) -> Self {
        let [nx, ny, nz] = spec.dims;
        Sidecar {
            shape: [nz, ny, nx],
            origin: spec.origin.into(),
            spacing: spec.step.into(),
            iso: ISO,
            layout: "float32 C order, value[z][y][x] at origin + (x, y, z) * spacing".into(),
            values: Some(Sidecar::hash(values)),
        }
    }

    /// The content hash a sidecar records for `values`.
    pub fn hash(values: &[f32]) -> String {
        format!("{:016x}", content_hash(&[bytemuck::cast_slice(values)]))
    }

    /// The sidecar path of an `.npy` path: same stem, `.json`.
    pub fn path_for(npy: &Path) -> std::path::PathBuf {
        npy.with_extension("json")
    }

    /// The grid it describes.
    pub fn spec(&self) -> Grid {
        let [nz, ny, nx] = self.shape;
        Grid {
            origin: Vec3::from(self.origin),
            step: Vec3::from(self.spacing),
            dims: [nx, ny, nz],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Field, Interval, eval_grid, falloff::sigma};

    /// `σ(z0 − z)`: solid below the plane `z = z0`.
    struct Ground(f32);

    impl Field for Ground {
        fn value(&self, p: Vec3) -> f32 {
            sigma(self.0 - p.z, 1.0)
        }
        fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
            (self.value(p), Vec3::ZERO)
        }
        fn support(&self) -> Aabb {
            Aabb::around(Vec3::ZERO, 10.0)
        }
        fn interval(&self, _b: &Aabb) -> Interval {
            Interval::new(0.0, 1.0)
        }
        fn lipschitz(&self) -> f32 {
            1.0
        }
        fn lipschitz_box(&self, _b: &Aabb) -> f32 {
            1.0
        }
    }

    #[test]
    fn samples_in_c_order_spanning_the_box() {
        let spec =
            grid_spanning(&Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 4.0)), [3, 2, 5]).unwrap();
        assert_eq!(spec.step, Vec3::ONE);
        let v = eval_grid(&Ground(2.0), &spec, None);
        assert_eq!(v.len(), 30);
        // Layer z = 2 is on the surface, below solid, above empty.
        assert!(v[..6].iter().all(|&x| x == 1.0));
        assert!(v[12..18].iter().all(|&x| x == ISO));
        assert!(v[24..].iter().all(|&x| x == 0.0));
        let s = Sidecar::new(&spec, &v);
        assert_eq!(s.values, Some(Sidecar::hash(&v)));
        assert_ne!(Sidecar::hash(&v), Sidecar::hash(&v[1..]));
        assert_eq!(s.shape, [5, 2, 3]);
        assert_eq!(s.spec(), spec);
        assert!(grid_spanning(&spec_box(), [0, 2, 2]).is_err());
        // One sample on an axis: the box's middle there, a flat box allowed.
        let plane = grid_spanning(&spec_box(), [1, 2, 2]).unwrap();
        assert_eq!((plane.origin.x, plane.step.x), (0.5, 0.0));
        let flat = Aabb::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 2.0, 1.0));
        assert_eq!(grid_spanning(&flat, [2, 1, 2]).unwrap().origin.y, 2.0);
        assert!(grid_spanning(&flat, [2, 2, 2]).is_err());
    }

    fn spec_box() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }
}
