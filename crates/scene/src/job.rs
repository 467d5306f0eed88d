//! The main job (`karstic run`): a tree file in, a mesh of its region, its texture masks
//! and a preview image out, with the time of every stage.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;

use crate::analysis::{Masks, Raster, texture_frame};
use crate::field::{Aabb, Field, Tree};
use crate::io::progress;
use crate::landform::feature_node;
use crate::mesh::export::{self, ExportOptions, Origin};
use crate::mesh::{GridSpec, Mesh, MeshOptions, MeshStats, polygonize};
use crate::picture::{self, guides};
use crate::render::camera::DEFAULT_FOV;
use crate::render::image::write_contact_sheet;
use crate::render::{Camera, Frame, Method, RenderSettings, cpu, views};
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
        progress: (!quiet)
            .then(|| progress(crate::mesh::polygonize::progress_steps(grid), what, false)),
        budget,
        ..MeshOptions::default()
    };
    let (mut mesh, stats) = polygonize(tree, grid, &opts)?;
    if let Some(b) = &opts.progress {
        b.finish_and_clear();
    }
    // A closed piece of a single sample is solid or air smaller than a cell: a speck, not
    // a surface the job's users can use (flakes of a cliff's rough faces, a crack a hair
    // narrower than a cell).
    mesh.drop_specks(SPECK);
    Ok((mesh, stats))
}

/// The most faces of a piece the job's meshes drop as a speck: the closed surface around
/// one sample.
pub const SPECK: usize = 8;

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
    let working = crate::io::spinner("compiling", opts.quiet);
    let compiled = file.compile_with(opts.budget)?;
    working.finish_and_clear();
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
    let t = Instant::now();
    let materials = picture::materials(&file.scene, &tree, ground.clone());
    stages.push(("materials", t.elapsed()));
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
        let fov = job.as_ref().map_or(DEFAULT_FOV, |j| j.fov.0);
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
    let settings = camera
        .as_ref()
        .map(|c| picture::settings_with(&file.scene, &tree, materials.clone(), c, Method::Segment));

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
                .unwrap_or(guides::BACKDROP_CELLS * cell);
            let sun = settings.as_ref().map(|s| s.shading.sun);
            let guides = guides::guides(
                &tree,
                || Ok(vec![guides::guide_on(&mesh, &grid, opts.budget)?]),
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
            // Each view traces at its own pixel's cone, along the guides meshed above, among
            // plants grown for its own camera (the preview's grew with its settings).
            let preview = camera;
            let look = |camera: &Camera| RenderSettings {
                trace: settings.trace.with_pixel_angle(camera.pixel_angle()),
                guides: guides.clone(),
                vegetation: match camera == &preview {
                    true => settings.vegetation.clone(),
                    false => picture::plants(&file.scene, &tree, &settings, camera),
                },
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
                    .unwrap_or((camera.width / 2, camera.height / 2));
                let fov = job.as_ref().map_or(DEFAULT_FOV, |j| j.fov.0);
                let mut frames = vec![frame];
                let features = file.scene.feature_names();
                // The features' views, then the views of the job's other names.
                let others = job.iter().flat_map(|j| j.views.keys());
                let others = others.filter(|n| !features.contains(&n.as_str()));
                let names: Vec<&str> = features
                    .iter()
                    .copied()
                    .chain(others.map(String::as_str))
                    .collect();
                for name in names {
                    let fixed = job.as_ref().and_then(|j| j.views.get(name));
                    let view = match (fixed, feature_node(&tree, name)) {
                        (Some(c), _) => Some(Camera::look_at(c.eye.0, c.target.0, fov, w, h)?),
                        (None, Some(id)) => {
                            let feature = tree.info(id).support.intersection(region);
                            views::feature_view(&tree, &guides, &feature, &materials, fov, (w, h))?
                        }
                        (None, None) => continue,
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
