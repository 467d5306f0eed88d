//! One picture setup for every command that draws a tree file: the camera, the tracing and
//! shading settings at the scene's scale, the water, the materials coloured by the
//! geology, and the guides ([`guides`]). `karstic run`, `render`, the editor, the tiles and
//! the GPU path all take their pictures' setup from here, so a tree gives the same picture
//! whichever command draws it.
//!
//! The renderer ([`crate::render`]) draws a field through a camera with given settings and
//! knows no tree file; this module reads the file's scene (its job's region, camera, field
//! of view, water level, snow line and sun, its geology) and makes those settings.

pub mod guides;

use std::sync::Arc;

use glam::Vec3;

use crate::analysis::flow::{self, FlowGraph};
use crate::dem::{Georef, HeightfieldField};
use crate::field::{Aabb, Field, Tree};
use crate::heightmap::{HeightmapGrid, TopOptions, heightmap};
use crate::render::camera::DEFAULT_FOV;
use crate::render::material::SnowLine;
use crate::render::shade::Water;
use crate::render::views::frame_surface;
use crate::render::{Camera, Materials, Method, RenderError, RenderSettings, TopCover, Vegetation};
use crate::scene::Scene;
use crate::scene::spec::Climate;

pub use guides::view_guides;

/// The materials of a tree file's scene: at the scale of [`scene_box`], over the compiled
/// scene's terrain, with the job's snow line, rock coloured by the scene's geology when it
/// has one, talus and streams on the top surface of its job's region ([`top_cover`]). The
/// preview, the feature views, the mesh colours and the texture masks all take theirs from
/// here.
pub fn materials(scene: &Scene, tree: &Tree, ground: Option<Arc<HeightfieldField>>) -> Materials {
    let mut m = materials_in(scene, tree.support(), ground);
    m.top = top_cover(scene, tree).map(Arc::new);
    m
}

/// The most column tops the raster of [`top_cover`] samples: its cell grows past
/// [`TOP_CELL`] to keep within it.
pub const TOP_COLUMNS: f32 = 160_000.0;

/// The finest cell (metres) of the raster of [`top_cover`]: a fallen block's size.
pub const TOP_CELL: f32 = 2.0;

/// The talus and streams on the top surface of a tree file's job region ([`TopCover`]):
/// the tops of `tree`'s columns over it ([`heightmap`], as `karstic heightmap` finds
/// them), their drainage routed down the steepest descent after the depressions are
/// filled (Priority-Flood + ε, [`crate::analysis::flow`]), so a stream crosses a carved
/// floor's hollows as water spilling through them does. `None` without a job (a tree
/// without one has no landscape's scale, as for [`vegetation`]) or where the region holds
/// too few columns.
pub fn top_cover(scene: &Scene, tree: &Tree) -> Option<TopCover> {
    scene.job.as_ref()?;
    let region = scene_box(scene, tree).intersection(tree.support());
    let size = region.size().truncate();
    if !(size.x > 0.0 && size.y > 0.0) {
        return None;
    }
    let cell = TOP_CELL.max((size.x * size.y / TOP_COLUMNS).sqrt());
    let grid = HeightmapGrid {
        origin: region.min.truncate(),
        cell: [f64::from(cell); 2],
        size: [
            (size.x / cell).floor() as usize + 1,
            (size.y / cell).floor() as usize + 1,
        ],
        georef: Georef::local(f64::from(cell), f64::from(cell)),
    };
    let opts = TopOptions {
        tolerance: 0.1 * cell,
        direct: true,
    };
    // At most `TOP_COLUMNS` samples: no budget to check.
    let tops = heightmap(tree, &grid, &opts, u64::MAX).ok()?.heightfield;
    let filled = flow::fill_depressions(&tops);
    let (nx, ny) = (tops.nx(), tops.ny());
    let mut graph = FlowGraph::new();
    graph.update(filled.samples(), nx, ny, cell, cell);
    let mut area = Vec::new();
    graph.accumulate(cell * cell, &mut area);
    TopCover::new(grid.origin, cell, (nx, ny), tops.samples().to_vec(), &area)
}

/// [`materials`] with `support` standing for the tree's support: the scale of a scene
/// without a job region, for consumers that compile only part of the tree (tiles take the
/// plan's region, the same for all of them).
pub fn materials_in(
    scene: &Scene,
    support: Aabb,
    ground: Option<Arc<HeightfieldField>>,
) -> Materials {
    let b = job_region(scene).unwrap_or(support);
    let mut m = Materials::for_scene(&b, ground);
    m.snow_line = scene
        .job
        .as_ref()
        .and_then(|j| j.snow_line)
        .map(|z| SnowLine::at(z.0, &b));
    m.geology = scene.geology().map(Arc::new);
    if m.geology.is_some() {
        // Talus is the hard beds' blocks (the soft ones weather to fines): their colour,
        // greyed by broken faces.
        m.scree = m.strata_rock.1.lerp(m.scree, 0.35);
    }
    if scene
        .job
        .as_ref()
        .is_some_and(|j| j.climate == Climate::Arid)
    {
        m.arid();
    }
    m
}

/// The settings of a picture of a tree file's scene: shading at the scale of its job's
/// region (else the support) with its job's water level, its [`materials`] over its
/// terrain `ground`.
pub fn settings(
    scene: &Scene,
    tree: &Tree,
    ground: Option<Arc<HeightfieldField>>,
    camera: &Camera,
    method: Method,
) -> RenderSettings {
    let materials = materials(scene, tree, ground);
    settings_with(scene, tree, materials, camera, method)
}

/// [`settings`] with the tree's `materials` already made (the job colours its mesh with
/// them too).
pub fn settings_with(
    scene: &Scene,
    tree: &Tree,
    materials: Materials,
    camera: &Camera,
    method: Method,
) -> RenderSettings {
    let mut s = RenderSettings {
        materials,
        // Edges supersampled: blind judges named the stair-stepped shadow edges.
        antialias: true,
        ..RenderSettings::for_scene(&scene_box(scene, tree), camera, method)
    };
    s.shading.water = scene
        .job
        .as_ref()
        .and_then(|j| j.water_level)
        .map(|z| Water::at(z.0));
    if let Some(sun) = scene.job.as_ref().and_then(|j| j.sun) {
        s.shading.sun = sun.direction();
    }
    s.vegetation = plants(scene, tree, &s, camera);
    s
}

/// The plants of a picture of `tree`'s scene through `camera` with `settings` (their
/// materials and water): [`vegetation`] grown for that camera, clear of its sight line;
/// `None` where none grow. Each of a job's views grows its own: they look where the
/// preview's camera does not.
pub fn plants(
    scene: &Scene,
    tree: &Tree,
    settings: &RenderSettings,
    camera: &Camera,
) -> Option<Arc<Vegetation>> {
    let grown = vegetation(scene, tree, settings, camera);
    clear_sight(Some(&grown).filter(|v| !v.is_empty()), camera)
}

/// `vegetation` clear of the sight line of `camera` to its target
/// ([`Vegetation::clear_sight`], a cone a third of the field of view wide).
pub fn clear_sight(vegetation: Option<&Vegetation>, camera: &Camera) -> Option<Arc<Vegetation>> {
    let spread = (camera.fov_y.to_radians() / 6.0).tan();
    vegetation.map(|v| Arc::new(v.clear_sight(camera.eye, camera.target, spread)))
}

/// A crown this wide (metres) spans a pixel where plants stop: farther, the haze and the
/// pixel's width leave nothing of them to see.
pub const FARTHEST_CROWN: f32 = 3.0;

/// Plants grow this far (metres) about the job's region whatever the camera, for the
/// feature views' cameras, which stand about it.
pub const NEAR_REGION: f32 = 300.0;

/// The trees and shrubs of a tree file's pictures: its job's climate's flora covering its
/// job's `vegetation` share (else the climate's) of the fit ground over the water, in
/// [`NEAR_REGION`] about [`scene_box`] (where the feature views look) and where `camera`
/// sees within the distance at which a crown [`FARTHEST_CROWN`] wide spans a pixel (a
/// job's region ends in the middle of its picture; the plants do not). A tree without a
/// job has none: its scale is not a landscape's (a spire, an arch alone).
pub fn vegetation(
    scene: &Scene,
    tree: &Tree,
    settings: &RenderSettings,
    camera: &Camera,
) -> Vegetation {
    let Some(job) = scene.job.as_ref() else {
        return Vegetation::default();
    };
    let (flora, cover) = job.climate.vegetation();
    let cover = job.vegetation.map_or(cover, |c| c.get());
    let region = scene_box(scene, tree);
    let support = tree.support();
    let far = FARTHEST_CROWN / camera.pixel_angle().max(1e-6);
    let eye = camera.eye.truncate();
    let seen = Aabb::new(
        (eye - glam::Vec2::splat(far)).extend(support.min.z),
        (eye + glam::Vec2::splat(far)).extend(support.max.z),
    );
    let near = region.dilate(NEAR_REGION);
    let grown = near.union(seen).intersection(support);
    let ahead = (camera.target - camera.eye).truncate();
    let level = ahead.length() > 0.3 * (camera.target - camera.eye).length();
    let aspect = camera.width as f32 / camera.height as f32;
    let half = ((camera.fov_y.to_radians() * 0.5).tan() * aspect).atan() + 0.2;
    let (forward, cos) = (ahead.normalize_or_zero(), half.min(3.0).cos());
    let within = |xy: glam::Vec2| {
        let d = xy - eye;
        let l = d.length();
        (near.min.x..=near.max.x).contains(&xy.x) && (near.min.y..=near.max.y).contains(&xy.y)
            || l < far && (!level || l < 50.0 || d.dot(forward) >= l * cos)
    };
    Vegetation::grow(
        tree,
        &settings.materials,
        &grown,
        &within,
        flora,
        cover,
        settings.shading.water.map(|w| w.level),
    )
}

/// The camera of a tree file's preview: looking from `look`'s eye at its target when
/// given, else the scene job's camera, else [`frame_surface`] of `field`; `fov` degrees,
/// else the job's, else [`DEFAULT_FOV`].
pub fn camera(
    scene: &Scene,
    field: &dyn Field,
    look: Option<(Vec3, Vec3)>,
    fov: Option<f32>,
    width: u32,
    height: u32,
) -> Result<Camera, RenderError> {
    let job = scene.job.as_ref();
    let look = look.or_else(|| job.and_then(|j| j.camera).map(|c| (c.eye.0, c.target.0)));
    let fov = fov.or(job.map(|j| j.fov.0)).unwrap_or(DEFAULT_FOV);
    match look {
        Some((eye, target)) => Camera::look_at(eye, target, fov, width, height),
        None => frame_surface(field, fov, width, height),
    }
}

/// The box that sets the scale of a scene's shading and materials: its job's region, or
/// the tree's support.
pub fn scene_box(scene: &Scene, tree: &Tree) -> Aabb {
    job_region(scene).unwrap_or_else(|| tree.support())
}

/// The region of the scene's job, when it gives one.
pub fn job_region(scene: &Scene) -> Option<Aabb> {
    let r = scene.job.as_ref()?.region?;
    Some(Aabb::new(r.min.0, r.max.0))
}
