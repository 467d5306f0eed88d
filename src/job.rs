//! The main job (`karstic run`): a tree file in, a mesh of its region, its texture masks
//! and a preview image out, with the time of every stage.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

use crate::analysis::{Masks, Raster, texture_frame};
use crate::field::{Aabb, Field, Node, NodeId, Tree};
use crate::io::progress;
use crate::landform::feature_node;
use crate::mesh::export::{self, ExportOptions, Origin};
use crate::mesh::{GridSpec, Mesh, MeshOptions, MeshStats, polygonize};
use crate::render::guide::Guide;
use crate::render::image::write_contact_sheet;
use crate::render::{Camera, Frame, Materials, Method, RenderSettings, cpu, views};
use crate::scene::{self, SceneFile};

/// What to run.
#[derive(Clone, Debug)]
pub struct JobOptions {
    /// Folder the outputs go to (created if needed).
    pub out_dir: PathBuf,
    /// Mesh the whole scene at the job's coarse cell size instead of its region.
    pub full: bool,
    /// Skip the preview image (and the feature views).
    pub no_render: bool,
    /// Skip the feature views.
    pub no_views: bool,
    /// No progress bars.
    pub quiet: bool,
    /// Memory budget of the DEMs, grids and image, in bytes.
    pub budget: u64,
    /// Where the mesh's origin lies.
    pub origin: Origin,
    /// Write the texture masks (over the region's footprint, at the mesh's cell size).
    pub masks: bool,
}

/// What a job made, and how long each stage took.
pub struct JobReport {
    /// The compiled tree.
    pub tree: Tree,
    /// The box that was meshed.
    pub region: Aabb,
    /// The cell size used.
    pub cell: f32,
    /// The mesh file.
    pub mesh_path: PathBuf,
    /// The preview image, if rendered.
    pub image_path: Option<PathBuf>,
    /// The feature views written, `(feature, image)`, then the contact sheet of the
    /// preview and the views (`("sheet", …)`) when there were any.
    pub views: Vec<(String, PathBuf)>,
    /// The texture masks and their sidecar, if written.
    pub mask_paths: Vec<PathBuf>,
    /// The mesh that was written.
    pub mesh: Mesh,
    /// Mesher statistics.
    pub mesh_stats: MeshStats,
    /// `(stage, duration)` in order.
    pub stages: Vec<(&'static str, Duration)>,
    /// Notices from loading (e.g. DEM units).
    pub notices: Vec<String>,
}

/// Cell of the backdrop guide, in cells of the region, when the job sets no `full_cell`.
const BACKDROP_CELLS: f32 = 6.0;

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
fn guides(
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
fn guide_on(mesh: &Mesh, grid: &GridSpec, budget: u64) -> anyhow::Result<Arc<Guide>> {
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
    job: Option<&crate::scene::spec::JobSpec>,
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

/// `tree` meshed over `grid` within `budget`, with a progress bar saying `what` unless
/// `quiet`.
fn mesh_with_bar(
    tree: &Tree,
    grid: &GridSpec,
    budget: u64,
    quiet: bool,
    what: &'static str,
) -> anyhow::Result<(Mesh, MeshStats)> {
    let opts = MeshOptions {
        progress: (!quiet).then(|| progress(0, "", false)),
        budget,
        ..MeshOptions::default()
    };
    if let Some(b) = &opts.progress {
        b.set_length(crate::mesh::polygonize::progress_steps(grid));
        b.set_message(what);
    }
    let out = polygonize(tree, grid, &opts)?;
    if let Some(b) = &opts.progress {
        b.finish_and_clear();
    }
    Ok(out)
}

/// The stem of the job's output files: the tree file's, not the scene's `name` (two
/// trees sharing a name must not overwrite each other's results), `_full` for a full job.
fn output_stem(path: &Path, opts: &JobOptions) -> String {
    let stem = path
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    match opts.full {
        true => format!("{stem}_full"),
        false => stem,
    }
}

/// Every file the job of `file` (at `path`) may write: the mesh, the preview, a view of
/// each feature, the contact sheet and the masks. Checked against the job's inputs before
/// anything is read or written ([`crate::io::check_outputs`]): a tree beside its DEM
/// `x.png` must not have its preview written over the DEM.
fn outputs(path: &Path, file: &SceneFile, opts: &JobOptions) -> Vec<PathBuf> {
    let stem = output_stem(path, opts);
    let dir = &opts.out_dir;
    let mut out = vec![dir.join(format!("{stem}.glb"))];
    if !opts.no_render {
        out.push(dir.join(format!("{stem}.png")));
        if !opts.no_views {
            let names = file.scene.feature_names();
            out.extend(names.iter().map(|n| dir.join(format!("{stem}_{n}.png"))));
            out.push(dir.join(format!("{stem}_sheet.png")));
        }
    }
    if opts.masks {
        out.extend(Masks::files(dir, &stem));
    }
    out
}

/// Runs the job of the tree file `path`. The job section was validated when the file
/// was loaded; the image is checked against the budget before meshing starts.
pub fn run(path: &Path, opts: &JobOptions) -> anyhow::Result<JobReport> {
    let mut stages = Vec::new();
    let t = Instant::now();
    let file: SceneFile = scene::load(path)?;
    crate::io::check_outputs(&file.inputs(), &outputs(path, &file, opts))?;
    let compiled = file.compile_with(opts.budget)?;
    stages.push(("load + compile", t.elapsed()));
    let tree = compiled.tree;
    let ground = compiled.ground;
    let mut notices = compiled.notices;
    let job = file.scene.job.clone();
    let support = tree.support();
    anyhow::ensure!(
        !support.is_empty(),
        "{}: the tree is empty everywhere",
        path.display()
    );
    let region_of_job = job
        .as_ref()
        .and_then(|j| j.region)
        .map(|r| Aabb::new(r.min.0, r.max.0));
    let region = match (opts.full, region_of_job) {
        (false, Some(r)) => r,
        _ => support,
    };
    // One material model for the mesh's colours, the masks and the pictures.
    let materials = Materials::for_tree(&file.scene, &tree, ground.clone());
    let fine = job
        .as_ref()
        .map_or(support.size().max_element() / 256.0, |j| j.cell.0);
    let cell = if opts.full {
        job.as_ref()
            .and_then(|j| j.full_cell.map(|c| c.0))
            .unwrap_or(4.0 * fine)
    } else {
        fine
    };
    let camera = if opts.no_render {
        None
    } else {
        let (w, h) = job.as_ref().map_or((1280, 720), |j| j.image);
        let fov = job.as_ref().map_or(40.0, |j| j.fov.0);
        let look = job
            .as_ref()
            .and_then(|j| j.camera)
            .filter(|_| !opts.full)
            .map(|c| (c.eye.0, c.target.0));
        Frame::check_budget(w, h, opts.budget)?;
        Some(match (look, region_of_job) {
            (Some(_), _) | (None, Some(_)) if !opts.full => Camera::view(look, &region, fov, w, h)?,
            _ => views::frame_surface(&tree, fov, w, h)?,
        })
    };

    // One picture setup for the preview and the views, as `render` and the editor make
    // it (water, geology colours, shading at the scene's scale).
    let settings = camera.as_ref().map(|c| {
        RenderSettings::with_materials(&file.scene, &tree, materials.clone(), c, Method::Segment)
    });

    // The masks and the mesh's UVs span the job's region, or the DEM for a full job.
    let frame = texture_frame(
        region_of_job.filter(|_| !opts.full).as_ref(),
        ground.as_deref(),
        &support,
    );
    let raster = match opts.masks {
        true => Some(Raster::new(frame, cell, opts.budget)?),
        false => None,
    };

    let t = Instant::now();
    let grid = GridSpec::with_cell(&region, cell)?;
    let (mesh, mesh_stats) = mesh_with_bar(&tree, &grid, opts.budget, opts.quiet, "meshing")?;
    stages.push(("polygonize", t.elapsed()));
    // The pictures follow the meshes: the region's, then a coarser one of what the
    // camera sees beyond it (`guide`).
    let guides = match &camera {
        Some(camera) => {
            let t = Instant::now();
            let backdrop_cell = job
                .as_ref()
                .and_then(|j| j.full_cell.map(|c| c.0))
                .unwrap_or(BACKDROP_CELLS * cell);
            let sun = settings.as_ref().map(|s| s.shading.sun);
            let guides = guides(
                &tree,
                || Ok(vec![guide_on(&mesh, &grid, opts.budget)?]),
                &grid,
                camera,
                sun,
                backdrop_cell,
                opts.budget,
            )?;
            stages.push(("guides", t.elapsed()));
            guides
        }
        None => Vec::new(),
    };

    std::fs::create_dir_all(&opts.out_dir)
        .with_context(|| format!("cannot create the output folder {}", opts.out_dir.display()))?;
    let stem = output_stem(path, opts);
    let mesh_path = opts.out_dir.join(format!("{stem}.glb"));
    let t = Instant::now();
    let export_opts = ExportOptions {
        albedo: Some(Arc::new(materials.clone())),
        origin: opts.origin,
        uv_frame: Some(frame),
    };
    export::write(&mesh, &mesh_path, &export_opts)?;
    stages.push(("write mesh", t.elapsed()));

    let mut views = Vec::new();
    let mut mask_paths = Vec::new();
    if let Some(raster) = raster {
        let t = Instant::now();
        let masks = Masks::compute(&tree, &materials, &raster);
        mask_paths = masks.write(&opts.out_dir, &stem)?;
        stages.push(("masks", t.elapsed()));
    }

    let image_path = match camera.zip(settings) {
        None => None,
        Some((camera, settings)) => {
            let t = Instant::now();
            // Each view traces at its own pixel's cone, along the guides meshed above.
            let look = |camera: &Camera| RenderSettings {
                trace: settings.trace.with_pixel_angle(camera.pixel_angle()),
                guides: guides.clone(),
                ..settings.clone()
            };
            let draw = |camera: &Camera, what: &str| {
                let tiles = camera.width.div_ceil(cpu::TILE) * camera.height.div_ceil(cpu::TILE);
                let bar = progress(tiles as u64, what, opts.quiet);
                let frame = cpu::render(&tree, camera, &look(camera), &bar);
                bar.finish_and_clear();
                frame
            };
            let frame = draw(&camera, "rendering");
            let image_path = opts.out_dir.join(format!("{stem}.png"));
            frame.write_png(&image_path)?;
            stages.push(("render", t.elapsed()));
            if !opts.no_views {
                let t = Instant::now();
                let (w, h) = job
                    .as_ref()
                    .and_then(|j| j.view_image)
                    .unwrap_or((camera.width / 3, camera.height / 3));
                let fov = job.as_ref().map_or(40.0, |j| j.fov.0);
                let mut frames = vec![frame];
                for name in file.scene.feature_names() {
                    let Some(id) = feature_node(&tree, name) else {
                        continue;
                    };
                    let fixed = job.as_ref().and_then(|j| j.views.get(name));
                    let view = match fixed {
                        Some(c) => Some(Camera::look_at(c.eye.0, c.target.0, fov, w, h)?),
                        None => {
                            let feature = tree.info(id).support.intersection(region);
                            views::feature_view(&tree, &guides, &feature, &materials, fov, (w, h))?
                        }
                    };
                    let Some(view) = view else {
                        notices.push(format!(
                            "feature {name:?}: no camera outside the terrain sees it; no view written"
                        ));
                        continue;
                    };
                    let frame = draw(&view, name);
                    let path = opts.out_dir.join(format!("{stem}_{name}.png"));
                    frame.write_png(&path)?;
                    views.push((name.to_string(), path));
                    frames.push(frame);
                }
                if frames.len() > 1 {
                    let path = opts.out_dir.join(format!("{stem}_sheet.png"));
                    write_contact_sheet(&path, &frames.iter().collect::<Vec<_>>())?;
                    views.push(("sheet".to_string(), path));
                }
                stages.push(("feature views", t.elapsed()));
            }
            Some(image_path)
        }
    };
    Ok(JobReport {
        tree,
        region,
        cell,
        mesh_path,
        image_path,
        views,
        mask_paths,
        mesh,
        mesh_stats,
        stages,
        notices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The backdrop guide is for terrain only: the main job's features all lie in its
    /// region, the hoodoo field's columns stand beyond it too.
    #[test]
    fn only_terrain_beyond_tells_terrain_from_features() {
        let region_of = |name: &str| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("trees")
                .join(name);
            let file = scene::load(&path).unwrap();
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
