//! Terrain analysis over the tree and its DEM: drainage ([`flow`]: depression filling and
//! multiple-flow-direction drainage area), slope, stream power, sinks and coastal
//! accessibility ([`relief`]), what vertical lines meet ([`column`]), and the
//! texture masks engines take as splat maps ([`masks`]).

pub mod column;
pub mod flow;
pub mod masks;
pub mod relief;

use crate::dem::HeightfieldField;
use crate::field::{Aabb, Rect};

pub use column::{Column, ColumnProbe};
pub use masks::{MaskError, Masks, Raster};

/// The rectangle the texture masks and the meshes' UVs span: `region`'s footprint when
/// one is given (a job's region, `--box`), else the terrain heightfield's extent (the DEM
/// frame), else the footprint of the tree's `support`.
pub fn texture_frame(
    region: Option<&Aabb>,
    ground: Option<&HeightfieldField>,
    support: &Aabb,
) -> Rect {
    match (region, ground) {
        (Some(r), _) => r.footprint(),
        (None, Some(g)) => g.heightfield().extent(),
        (None, None) => support.footprint(),
    }
}
