//! Meshing the S-field leaf: bound-pruned Marching Cubes ([`crate::mesh::polygonize`])
//! over its domain box, at its finest voxel size unless told otherwise.

use super::SField;
use crate::field::Field;
use crate::mesh::{GridSpec, Mesh, MeshError, MeshOptions, MeshStats, polygonize};

impl SField {
    /// The grid [`SField::extract`] samples: the domain box cut into cells of about `cell`
    /// metres (the finest voxel when `None`), samples on the voxel nodes.
    pub fn mesh_grid(&self, cell: Option<f32>) -> Result<GridSpec, MeshError> {
        let p = self.params();
        GridSpec::with_cell(&p.domain, cell.unwrap_or(p.voxel))
    }

    /// The surface `f = T` as a welded, closed mesh (the field fades to 0 inside the
    /// domain's faces, so the solid never touches the grid's border), normals out of the
    /// solid. Empty when the field is.
    pub fn extract(
        &self,
        cell: Option<f32>,
        opts: &MeshOptions,
    ) -> Result<(Mesh, MeshStats), MeshError> {
        let grid = self.mesh_grid(cell)?;
        polygonize(self as &dyn Field, &grid, opts)
    }
}
