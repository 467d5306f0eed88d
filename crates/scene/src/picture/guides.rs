//! The guides of a picture ([`Guide`]): meshes of what the camera sees, finest near the
//! eye, whose cells tell the tracer where the surface can be, so rays skip the empty
//! space in steps of a mesh's BVH instead of a march. The job meshes its region and
//! guides by it; `render` and the editor mesh the part of the job's region their camera
//! sees ([`view_guides`]); both add a coarse backdrop of the terrain beyond ([`guides`]).

use std::sync::Arc;

use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::field::{Aabb, Field, Node, NodeId, Tree};
use crate::io::progress;
use crate::mesh::{GridSpec, Mesh, MeshOptions, polygonize};
use crate::render::Camera;
use crate::render::guide::Guide;
use crate::scene::spec::JobSpec;

/// Cell of the backdrop guide, in cells of the region, when the job sets no `full_cell`.
pub const BACKDROP_CELLS: f32 = 6.0;

/// Ratio of the cells of successive levels of a guide ([`levels`]).
const GUIDE_GROWTH: f32 = 2.0;

/// Most backdrop levels; the last one takes all the rest of what the camera sees.
const BACKDROP_LEVELS: usize = 3;

/// Most levels of the region's guide in [`view_guides`]: its cells are at most four of
/// the job's.
const REGION_LEVELS: usize = 3;

/// The levels of a guide over `seen` for a picture through `camera`, as `(box, cell)`:
/// the first at `cell`, each next [`GUIDE_GROWTH`] times coarser. A level covers the part
/// of `seen` within the distance of the eye where the next level's cells would span more
/// than [`GUIDE_MAX_CELL_PIXELS`] pixels; the last one (at most `max`) all the rest. So
/// every level but the first guides only where its cells span at most that many pixels:
/// outside the finer levels' boxes, which are centred on the eye.
fn levels(camera: &Camera, seen: &Aabb, cell: f32, max: usize) -> Vec<(Aabb, f32)> {
    let mut out = Vec::new();
    let mut cell = cell;
    for level in 0..max {
        let next = cell * GUIDE_GROWTH;
        let reach = Vec3::splat(next / (GUIDE_MAX_CELL_PIXELS * camera.pixel_angle()));
        let near = match level + 1 < max {
            true => seen.intersection(Aabb::new(camera.eye - reach, camera.eye + reach)),
            false => *seen,
        };
        if !near.is_empty() {
            out.push((near, cell));
        }
        if near.contains_box(seen) {
            break;
        }
        cell = next;
    }
    out
}

/// The guides of the job's pictures ([`Guide`]): the region's (`region` makes them over
/// `grid`'s box, finest first, at `grid`'s cell or coarser), then, when `camera` sees
/// beyond that box and all the tree has there is terrain ([`only_terrain_beyond`]),
/// backdrop meshes of the box of the support it sees ([`seen_box`]) swept along the
/// shadow rays towards `sun` (a unit vector; `None` without shadows) up to the support's
/// top, in [`levels`]: the first at `backdrop_cell`, each next [`GUIDE_GROWTH`] times
/// coarser, so the far hills the view grazes cost a coarse mesh, not a march. Marching
/// near the ground where no mesh is costs most of a picture's time; the backdrop's
/// meshing and BVH cost a small part of it.
///
/// Every mesh is made side by side with the others: each ends in a BVH build on one
/// core, which the others' meshing overlaps.
pub fn guides(
    tree: &Tree,
    region: impl FnOnce() -> anyhow::Result<Vec<Arc<Guide>>> + Send,
    grid: &GridSpec,
    camera: &Camera,
    sun: Option<Vec3>,
    backdrop_cell: f32,
    budget: u64,
) -> anyhow::Result<Vec<Arc<Guide>>> {
    let (guides, backdrop) = rayon::join(region, || {
        backdrop_guides(tree, grid, camera, sun, backdrop_cell, budget)
    });
    let mut guides = guides?;
    guides.extend(backdrop?);
    Ok(guides)
}

/// The backdrop guides of [`guides`] beyond the region of `grid`.
fn backdrop_guides(
    tree: &Tree,
    grid: &GridSpec,
    camera: &Camera,
    sun: Option<Vec3>,
    backdrop_cell: f32,
    budget: u64,
) -> anyhow::Result<Vec<Arc<Guide>>> {
    let support = tree.support();
    let seen = seen_box(camera, &support);
    let seen = match sun {
        Some(sun) if sun.z > 0.0 && !seen.is_empty() => {
            let rise = sun * ((support.max.z - seen.min.z) / sun.z);
            seen.union(Aabb::new(seen.min + rise, seen.max + rise))
        }
        _ => seen,
    }
    .intersection(support);
    let region = grid.bounds();
    if seen.is_empty()
        || region.contains_box(&seen)
        || backdrop_cell <= grid.spacing.max_element()
        || !only_terrain_beyond(tree, tree.root(), &region)
    {
        return Ok(Vec::new());
    }
    let grids = levels(camera, &seen, backdrop_cell, BACKDROP_LEVELS)
        .into_iter()
        .map(|(b, c)| GridSpec::with_cell(&b, c))
        .collect::<Result<Vec<_>, _>>()?;
    guides_on(tree, &grids, budget, None)
}

/// The guides of `tree` meshed over each of `grids`, side by side, advancing `progress`.
fn guides_on(
    tree: &Tree,
    grids: &[GridSpec],
    budget: u64,
    progress: Option<ProgressBar>,
) -> anyhow::Result<Vec<Arc<Guide>>> {
    grids
        .par_iter()
        .map(|grid| {
            let opts = MeshOptions {
                progress: progress.clone(),
                budget,
                ..MeshOptions::default()
            };
            let (mesh, _) = polygonize(tree, grid, &opts)?;
            guide_on(&mesh, grid, budget)
        })
        .collect()
}

/// The guide of `mesh`, made over `grid`: its occupancy cells are the grid's.
pub fn guide_on(mesh: &Mesh, grid: &GridSpec, budget: u64) -> anyhow::Result<Arc<Guide>> {
    let cell = grid.spacing.max_element();
    Ok(Arc::new(Guide::from_mesh(
        mesh,
        &grid.bounds(),
        cell,
        budget,
    )?))
}

/// The most pixels a cell of the job's mesh may span where the view enters the region for
/// [`view_guides`] to guide the picture by it, and a cell of any guide's level beyond the
/// first where that level guides ([`levels`]).
pub const GUIDE_MAX_CELL_PIXELS: f32 = 8.0;

/// The guides of a picture of `tree` through `camera` ([`Guide`]): when the scene's `job`
/// has a region the camera sees, from far enough that a cell spans at most
/// [`GUIDE_MAX_CELL_PIXELS`] pixels where the view enters it, the part of it the camera
/// sees ([`seen_cells`]) meshed in [`levels`] on the job's lattice: at the job's cell
/// near the eye, then [`GUIDE_GROWTH`] times coarser each (at most [`REGION_LEVELS`])
/// where those cells still span at most [`GUIDE_MAX_CELL_PIXELS`] pixels; then the
/// backdrop ([`guides`]); none otherwise. What a guide gives up (solid thinner than its
/// cell) is a few pixels at most. Closer, the solid a cell misses (a low bump of a
/// near-`T` field, a grazed ledge) would fill patches of the picture, so the whole field
/// is traced.
pub fn view_guides(
    tree: &Tree,
    job: Option<&JobSpec>,
    camera: &Camera,
    sun: Option<Vec3>,
    budget: u64,
    quiet: bool,
) -> anyhow::Result<Vec<Arc<Guide>>> {
    let Some(job) = job else {
        return Ok(Vec::new());
    };
    let Some(region) = job.region.map(|r| Aabb::new(r.min.0, r.max.0)) else {
        return Ok(Vec::new());
    };
    let cell = job.cell.0;
    let nearest = region.distance(camera.eye) * camera.pixel_angle();
    if cell > GUIDE_MAX_CELL_PIXELS * nearest {
        return Ok(Vec::new());
    }
    let Some(seen) = seen_cells(camera, &region, cell) else {
        return Ok(Vec::new());
    };
    let grids = levels(camera, &seen, cell, REGION_LEVELS)
        .into_iter()
        .map(|(b, c)| GridSpec::with_cell(&on_lattice(&b, &region, c), c))
        .collect::<Result<Vec<_>, _>>()?;
    let backdrop = job.full_cell.map_or(BACKDROP_CELLS * cell, |c| c.0);
    let region = || {
        let bar = (!quiet).then(|| progress(0, "meshing the job's region", false));
        if let Some(b) = &bar {
            b.set_length(
                grids
                    .iter()
                    .map(crate::mesh::polygonize::progress_steps)
                    .sum(),
            );
        }
        let guides = guides_on(tree, &grids, budget, bar.clone());
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        guides
    };
    guides(
        tree,
        region,
        &GridSpec::with_cell(&seen, cell)?,
        camera,
        sun,
        backdrop,
        budget,
    )
}

/// Rays per side of the image [`seen_cells`] follows.
const SEEN_RAYS: u32 = 17;

/// The part of `region` that `camera` sees, on the lattice of `cell`-sided cells from the
/// region's corner, padded by a cell: the box of a grid of pixel rays' spans through the
/// region; `None` when none crosses it. Rays between the grid's miss a sliver of what the
/// camera sees, which is then traced without a guide: a guide speeds the march up, the
/// picture does not depend on where it stops.
fn seen_cells(camera: &Camera, region: &Aabb, cell: f32) -> Option<Aabb> {
    let seen = seen_box(camera, region);
    (!seen.is_empty()).then(|| on_lattice(&seen, region, cell))
}

/// The box `b` grown to the lattice of `cell`-sided cells from `region`'s corner and
/// padded by a cell, inside `region`.
fn on_lattice(b: &Aabb, region: &Aabb, cell: f32) -> Aabb {
    let lo = ((b.min - region.min) / cell).floor() - Vec3::ONE;
    let hi = ((b.max - region.min) / cell).ceil() + Vec3::ONE;
    Aabb::new(region.min + lo * cell, region.min + hi * cell).intersection(*region)
}

/// The box of the spans through `b` of a grid of [`SEEN_RAYS`]² pixel rays of `camera`
/// (empty when none crosses it): about the part of `b` the camera sees.
fn seen_box(camera: &Camera, b: &Aabb) -> Aabb {
    let n = SEEN_RAYS - 1;
    let (w, h) = (camera.width - 1, camera.height - 1);
    (0..=n)
        .flat_map(|a| (0..=n).map(move |c| (a * w / n, c * h / n)))
        .map(|(i, j)| camera.pixel_ray(i, j))
        .filter_map(|r| {
            r.clip(b)
                .map(|(t0, t1)| Aabb::from_points([r.at(t0), r.at(t1)]))
        })
        .fold(Aabb::EMPTY, Aabb::union)
}

/// True when every part of the subtree `id` whose support reaches outside `region` is a
/// heightfield leaf: the ground, which a coarse mesh follows to within its detail. A
/// coarse mesh would lose anything thinner than its cells (a hoodoo's cap, a thin
/// arch), so the backdrop guide is only used over terrain. Warps and affine maps, whose
/// children's supports are in their own frames, count as more than terrain.
fn only_terrain_beyond(tree: &Tree, id: NodeId, region: &Aabb) -> bool {
    let support = tree.info(id).support;
    if support.is_empty() || region.contains_box(&support) {
        return true;
    }
    match &tree.nodes()[id as usize] {
        Node::Leaf(f) => f
            .as_any()
            .is_some_and(|a| a.is::<crate::dem::HeightfieldField>()),
        Node::Blend { .. }
        | Node::Union(_)
        | Node::Intersection(_)
        | Node::Difference { .. }
        | Node::Replace { .. } => tree.nodes()[id as usize]
            .children()
            .into_iter()
            .all(|c| only_terrain_beyond(tree, c, region)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// The backdrop guide is for terrain only: the main job's features all lie in its
    /// region, the hoodoo field's columns stand beyond it too.
    #[test]
    fn only_terrain_beyond_tells_terrain_from_features() {
        let region_of = |name: &str| {
            // The repository's trees, two levels above this crate.
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../trees")
                .join(name);
            let file = crate::scene::load(&path).unwrap();
            let r = file.scene.job.as_ref().and_then(|j| j.region).unwrap();
            (file.compile().unwrap().tree, Aabb::new(r.min.0, r.max.0))
        };
        let (caves, region) = region_of("jacksboro_caves.ron");
        assert!(only_terrain_beyond(&caves, caves.root(), &region));
        let small = Aabb::new(region.min, region.min + 0.5 * region.size());
        assert!(!only_terrain_beyond(&caves, caves.root(), &small));
        let (hoodoos, region) = region_of("hoodoo_field.ron");
        assert!(!only_terrain_beyond(&hoodoos, hoodoos.root(), &region));
    }
}
