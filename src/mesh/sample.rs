//! Sampling a field on a dense grid (`karstic sample`) and the JSON sidecar that tells
//! other tools where the samples are.

use std::path::Path;

use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::MeshError;
use crate::field::{Aabb, Field, T};

/// A dense grid of samples: `dims = [nx, ny, nz]` points from `origin` every `spacing`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSpec {
    /// Position of sample `(0, 0, 0)`.
    pub origin: Vec3,
    /// Distance between neighbouring samples.
    pub spacing: Vec3,
    /// Samples per axis.
    pub dims: [usize; 3],
}

impl SampleSpec {
    /// `dims` samples spanning `b` corner to corner (each axis needs at least 2).
    pub fn spanning(b: &Aabb, dims: [usize; 3]) -> Result<Self, MeshError> {
        if dims.iter().any(|&d| d < 2) {
            return Err(MeshError::GridShape(format!(
                "resolution {}×{}×{}: each axis needs at least 2 samples",
                dims[0], dims[1], dims[2]
            )));
        }
        let size = b.size();
        if b.is_empty() || !size.is_finite() || size.min_element() <= 0.0 {
            return Err(MeshError::GridShape(format!(
                "box {} .. {}: expected a finite box with positive size on every axis",
                b.min, b.max
            )));
        }
        let steps = Vec3::new(dims[0] as f32 - 1.0, dims[1] as f32 - 1.0, dims[2] as f32 - 1.0);
        Ok(SampleSpec {
            origin: b.min,
            spacing: size / steps,
            dims,
        })
    }

    /// Number of samples.
    pub fn len(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// True when there is no sample (never, for a spec built by [`SampleSpec::spanning`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes the samples take as `f32`.
    pub fn bytes(&self) -> u64 {
        self.len() * 4
    }
}

/// Evaluates `field` at every sample, in C order (`x` fastest): one
/// [`Field::eval_block`] per z-layer, layers in parallel. Advances `progress` per layer.
pub fn sample_field(field: &dyn Field, spec: &SampleSpec, progress: Option<&ProgressBar>) -> Vec<f32> {
    let [nx, ny, nz] = spec.dims;
    let mut values = vec![0f32; nx * ny * nz];
    values.par_chunks_mut(nx * ny).enumerate().for_each(|(k, layer)| {
        let origin = spec.origin + Vec3::new(0.0, 0.0, k as f32 * spec.spacing.z);
        field.eval_block(origin, spec.spacing, [nx, ny, 1], layer);
        if let Some(p) = progress {
            p.inc(1);
        }
    });
    values
}

/// The JSON sidecar of a sampled `.npy` grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
}

impl Sidecar {
    /// The sidecar of `spec`.
    pub fn new(spec: &SampleSpec) -> Self {
        let [nx, ny, nz] = spec.dims;
        Sidecar {
            shape: [nz, ny, nx],
            origin: spec.origin.into(),
            spacing: spec.spacing.into(),
            iso: T,
            layout: "float32 C order, value[z][y][x] at origin + (x, y, z) * spacing".into(),
        }
    }

    /// The sidecar path of an `.npy` path: same stem, `.json`.
    pub fn path_for(npy: &Path) -> std::path::PathBuf {
        npy.with_extension("json")
    }

    /// The grid it describes.
    pub fn spec(&self) -> SampleSpec {
        let [nz, ny, nx] = self.shape;
        SampleSpec {
            origin: Vec3::from(self.origin),
            spacing: Vec3::from(self.spacing),
            dims: [nx, ny, nz],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Interval, falloff::sigma};

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
        let spec = SampleSpec::spanning(&Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 4.0)), [3, 2, 5]).unwrap();
        assert_eq!(spec.spacing, Vec3::ONE);
        let v = sample_field(&Ground(2.0), &spec, None);
        assert_eq!(v.len(), 30);
        // Layer z = 2 is on the surface, below solid, above empty.
        assert!(v[..6].iter().all(|&x| x == 1.0));
        assert!(v[12..18].iter().all(|&x| x == T));
        assert!(v[24..].iter().all(|&x| x == 0.0));
        let s = Sidecar::new(&spec);
        assert_eq!(s.shape, [5, 2, 3]);
        assert_eq!(s.spec(), spec);
        assert!(SampleSpec::spanning(&spec_box(), [1, 2, 2]).is_err());
    }

    fn spec_box() -> Aabb {
        Aabb::new(Vec3::ZERO, Vec3::ONE)
    }
}
