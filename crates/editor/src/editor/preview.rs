//! The viewport's renderer: the CPU tracer on a background thread, so the interface never
//! waits for it.
//!
//! Each request is drawn first as a *fast pass*: a sixteenth of the side for the first
//! image, then the size that the last passes' cost per pixel says fits in
//! [`DRAG_BUDGET`] (between an eighth and a thirty-second of the side), without shadow
//! rays or occlusion samples and with the surface tolerance at a whole pixel's footprint
//! (a few thousandths of the full image's work), shown at once. While the view or a
//! value is dragged, only fast passes are drawn. Otherwise the full image follows,
//! shaded as `karstic render` shades it: on the CPU, band by band over the enlarged fast
//! pass (so the refinement costs what the command line's render costs, plus the fast
//! pass), or in one dispatch of the wgpu tracer over the tree's tape
//! ([`crate::render::gpu`]) when the [`Backend`] says so. A newer request stops the CPU
//! work under way before its next tile.
//!
//! The scene is compiled once per version and the compiled tree kept for every image of
//! that version (views and sizes change nothing of it); so is its tape for the GPU.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

use super::points::{Handle, handles};
use crate::compile::{Compiled, compile_scene};
use crate::field::Aabb;
use crate::render::cpu::{Bands, antialias, render_bands};
use crate::render::gpu::GpuContext;
use crate::render::trace::normal;
use crate::render::{Camera, Frame, Method, RenderSettings, cpu};
use crate::scene::Scene;
use crate::tape::Tape;

/// The fast pass is at most this fraction of the image's side.
pub const FAST_DIVISOR: u32 = 8;

/// The first fast pass, before any cost was measured, is this fraction of the side.
pub const FIRST_DIVISOR: u32 = 16;

/// The fast pass is at least this fraction of the side, however slow the last ones were.
pub const COARSEST_DIVISOR: u32 = 32;

/// The fast pass's surface tolerance, in pixel footprints (a full image's is half of one):
/// at its size a finer hit changes no pixel, and the march near the surface is shorter.
const FAST_CONE: f32 = 2.0;

/// Time one preview may take while something is dragged: ten previews a second.
pub const DRAG_BUDGET: Duration = Duration::from_millis(80);

/// Shortest time between two partial images of a refinement sent to the interface.
const PARTIAL_EVERY: Duration = Duration::from_millis(150);

/// An orbit camera in the convention of DCC tools: it turns about a target point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// The point turned about.
    pub target: Vec3,
    /// Distance from the target to the eye, metres.
    pub distance: f32,
    /// Azimuth of the eye about the target (radians from +X, counter-clockwise).
    pub yaw: f32,
    /// Elevation of the eye above the target (radians).
    pub pitch: f32,
    /// Vertical field of view, degrees.
    pub fov: f32,
}

impl Orbit {
    /// The orbit through `camera`'s eye about its target.
    pub fn from_camera(camera: &Camera) -> Self {
        let d = camera.eye - camera.target;
        let distance = d.length().max(1e-3);
        Orbit {
            target: camera.target,
            distance,
            yaw: d.y.atan2(d.x),
            pitch: (d.z / distance).clamp(-1.0, 1.0).asin(),
            fov: camera.fov_y,
        }
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * cy, cp * sy, sp)
    }

    /// The camera for a `width × height` image.
    pub fn camera(&self, width: u32, height: u32) -> Option<Camera> {
        Camera::look_at(self.eye(), self.target, self.fov, width, height).ok()
    }

    /// Turns the eye by a pointer motion of `(dx, dy)` points.
    pub fn turn(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.5, 1.5);
    }

    /// Moves the target and the eye with a pointer motion of `(dx, dy)` pixels in a view
    /// `height` pixels tall: the point under the pointer stays under it at the target.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let Some(c) = self.camera(16, 16) else {
            return;
        };
        let (right, up, _, tan) = c.basis();
        let per_pixel = 2.0 * self.distance * tan / height.max(1.0);
        self.target += (up * dy - right * dx) * per_pixel;
    }

    /// Moves the eye towards the target (`amount > 0`) or away.
    pub fn dolly(&mut self, amount: f32) {
        self.distance = (self.distance * (-amount * 0.004).exp()).max(0.5);
    }
}

/// What the viewport shows of an image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Look {
    /// Shaded as `karstic render` shades it.
    #[default]
    Shaded,
    /// Field evaluations per primary ray (`karstic render --cost`'s ramp).
    Cost,
    /// The surface's outward normal as a colour: `(n + 1) / 2` in RGB.
    Normals,
}

/// How much of the shading an image gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// No shadow rays and no occlusion samples: the fast pass and the drag previews.
    Fast,
    /// As `karstic render`.
    Full,
}

/// Which tracer draws the viewport's refined images (the fast passes are the CPU's).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The wgpu tracer when the default adapter is a hardware one, else the CPU's.
    #[default]
    Auto,
    /// The CPU tracer.
    Cpu,
    /// The wgpu tracer on any adapter, software ones (lavapipe) included.
    Gpu,
}

/// What to draw.
#[derive(Clone, Debug)]
pub struct Request {
    /// The scene (the file's, or a preview of an edit being dragged).
    pub scene: Arc<Scene>,
    /// Changes whenever `scene` does: the scene is compiled again only then.
    pub version: u64,
    /// The view; `None`: the scene's preview camera (its job's, else framed).
    pub view: Option<Orbit>,
    /// Full image size, pixels.
    pub size: (u32, u32),
    /// Only the fast pass (while a value or the view is being dragged).
    pub coarse: bool,
    /// Whether the images should carry their normals' colours ([`Rendered::normals`]).
    pub normals: bool,
    /// The node an edit just changed: the rows its support covers (before and after the
    /// edit) are refined first.
    pub focus: Option<String>,
}

/// A drawn image.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The image and its depths.
    pub frame: Frame,
    /// The camera it was drawn through.
    pub camera: Camera,
    /// Of which request (its scene version).
    pub version: u64,
    /// The last image of its request, complete: nothing more will come for it.
    pub settled: bool,
    /// How it was shaded.
    pub quality: Quality,
    /// Time from the request to this image.
    pub latency: Duration,
    /// With [`Request::normals`]: the colours of the surface normals (RGBA8, the sky
    /// black), for the rows drawn so far.
    pub normals: Option<Vec<u8>>,
    /// The Feature Curve control points of the scene, where they are in the world.
    pub handles: Arc<Vec<Handle>>,
    /// Which tracer drew it: `"CPU"`, `"GPU (adapter)"`, or the CPU and why not the GPU.
    pub tracer: String,
}

/// What the renderer reports.
#[derive(Debug)]
pub enum Report {
    /// An image.
    Image(Box<Rendered>),
    /// The scene could not be compiled, or no camera placed.
    Failed {
        /// Of which scene version.
        version: u64,
        /// Why.
        message: String,
    },
}

/// What the render thread is asked for.
enum Job {
    /// Compile a scene version ahead of its first image (the file just opened or
    /// reloaded: the window's first frame need not wait for it).
    Compile(Arc<Scene>, u64),
    /// Draw, as request number `.0`.
    Draw(u64, Request),
}

/// The background renderer.
pub struct Preview {
    requests: Sender<Job>,
    reports: Receiver<Report>,
    /// Counts the requests: the thread stops an image whose request is not the latest.
    latest: Arc<AtomicU64>,
    /// The render thread, joined on drop.
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Preview {
    /// Stops the CPU's image under way and waits for the render thread to end, so that a
    /// GPU device it opened is closed before the process exits (one left open while the
    /// process exits corrupted the heap of lavapipe's driver).
    fn drop(&mut self) {
        self.latest.fetch_add(1, Ordering::SeqCst);
        // Dropping the only sender ends the thread's loop.
        self.requests = channel().0;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Preview {
    /// Starts the render thread for scenes of the tree file at `path` (asset paths are
    /// relative to its folder), refining on `backend`; `wake` is called after each report
    /// (a repaint request).
    pub fn start(path: &Path, backend: Backend, wake: impl Fn() + Send + 'static) -> Self {
        let (requests, incoming) = channel();
        let (outgoing, reports) = channel();
        let latest = Arc::new(AtomicU64::new(0));
        let server = Server {
            path: path.to_path_buf(),
            latest: latest.clone(),
            out: outgoing,
            wake: Box::new(wake),
            ready: None,
            per_pixel: Default::default(),
            backend,
            gpu: None,
        };
        let thread = std::thread::Builder::new()
            .name("karstic-preview".into())
            .spawn(move || server.serve(&incoming))
            .expect("spawning the preview thread");
        Preview {
            requests,
            reports,
            latest,
            thread: Some(thread),
        }
    }

    /// Asks for an image; the work on older requests stops.
    pub fn request(&self, request: Request) {
        let id = self.latest.fetch_add(1, Ordering::SeqCst) + 1;
        // The thread ends only with this handle, so the send cannot fail while it lives.
        let _ = self.requests.send(Job::Draw(id, request));
    }

    /// Compiles `scene` (as `version`) now, so that its first image only traces: the
    /// editor calls it as soon as a file is read, before its window shows a frame. A
    /// compilation error is reported as for a drawing.
    pub fn prepare(&self, scene: Arc<Scene>, version: u64) {
        let _ = self.requests.send(Job::Compile(scene, version));
    }

    /// The reports that arrived since the last call.
    pub fn poll(&self) -> Vec<Report> {
        self.reports.try_iter().collect()
    }
}

/// The scene compiled for a version, with its control points.
struct Ready {
    version: u64,
    /// The scene it was compiled from (where an edited node was, for the next version).
    scene: Arc<Scene>,
    compiled: Compiled,
    handles: Arc<Vec<Handle>>,
    /// Its encoding for the GPU (built on the first GPU image), or why it has none.
    tape: Option<Result<Tape, String>>,
}

/// The GPU as the render thread found it when first asked.
enum Gpu {
    /// Open, with its pipelines.
    Open(Box<GpuContext>),
    /// Not used, and why.
    Off(String),
}

/// The render thread's state.
struct Server {
    path: std::path::PathBuf,
    latest: Arc<AtomicU64>,
    out: Sender<Report>,
    wake: Box<dyn Fn() + Send>,
    ready: Option<Ready>,
    /// Seconds per pixel of the last fast pass.
    per_pixel: std::cell::Cell<Option<f64>>,
    /// The tracer asked for the refined images.
    backend: Backend,
    /// Opened on the first refined image (never with [`Backend::Cpu`]).
    gpu: Option<Gpu>,
}

/// The image size that fits `per_pixel` seconds per pixel in `budget`, for a `size`
/// view: an integer fraction of it, between [`FAST_DIVISOR`] and [`COARSEST_DIVISOR`] of
/// its side ([`FIRST_DIVISOR`] when no cost is known yet), at least one pixel.
pub fn fast_size(size: (u32, u32), per_pixel: Option<f64>, budget: Duration) -> (u32, u32) {
    let pixels = size.0 as f64 * size.1 as f64;
    let div = per_pixel.map_or(FIRST_DIVISOR, |c| {
        let want = (pixels * c / budget.as_secs_f64()).sqrt();
        (want.ceil() as u32).clamp(FAST_DIVISOR, COARSEST_DIVISOR)
    });
    ((size.0 / div).max(1), (size.1 / div).max(1))
}

impl Server {
    fn serve(mut self, incoming: &Receiver<Job>) {
        while let Ok(mut next) = incoming.recv() {
            while let Ok(newer) = incoming.try_recv() {
                next = newer;
            }
            match next {
                Job::Compile(scene, version) => {
                    self.compile(&scene, version);
                }
                Job::Draw(id, req) => self.draw_request(id, &req),
            }
        }
    }

    fn send(&self, report: Report) {
        let _ = self.out.send(report);
        (self.wake)();
    }

    fn fail(&self, version: u64, message: String) {
        self.send(Report::Failed { version, message });
    }

    /// The compiled scene of `version`, compiled now if it is not yet.
    fn compile(&mut self, scene: &Arc<Scene>, version: u64) -> bool {
        if self.ready.as_ref().map(|r| r.version) == Some(version) {
            return true;
        }
        self.ready = None;
        let base = self
            .path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        match compile_scene(scene, &self.path, &base) {
            Ok(compiled) => {
                let handles = Arc::new(handles(scene, compiled.ground.as_deref()));
                self.ready = Some(Ready {
                    version,
                    scene: scene.clone(),
                    compiled,
                    handles,
                    tape: None,
                });
                true
            }
            Err(e) => {
                self.fail(version, crate::io::chain(&e));
                false
            }
        }
    }

    /// The GPU to refine on, opened on first use as the backend says; `Err`: why the
    /// CPU refines instead (`None` for [`Backend::Cpu`], which needs no reason).
    fn gpu(&mut self) -> Result<&GpuContext, Option<String>> {
        let backend = self.backend;
        let gpu = self.gpu.get_or_insert_with(|| {
            let open = |software_ok: bool| match GpuContext::default_adapter() {
                Ok((name, true)) if !software_ok => Gpu::Off(format!(
                    "the only GPU adapter is a software one ({name}), slower than the CPU (use it with --gpu)"
                )),
                Ok(_) => match GpuContext::new() {
                    Ok(ctx) => Gpu::Open(Box::new(ctx)),
                    Err(e) => Gpu::Off(crate::io::chain(&e)),
                },
                Err(e) => Gpu::Off(crate::io::chain(&e)),
            };
            match backend {
                Backend::Cpu => Gpu::Off(String::new()),
                Backend::Auto => open(false),
                Backend::Gpu => open(true),
            }
        });
        match gpu {
            Gpu::Open(ctx) => Ok(ctx),
            Gpu::Off(why) if why.is_empty() => Err(None),
            Gpu::Off(why) => Err(Some(why.clone())),
        }
    }

    /// The refined image of `camera` on the GPU, or why not (`None`: the CPU was asked).
    fn gpu_image(
        &mut self,
        scene: &Scene,
        camera: &Camera,
    ) -> Result<(Frame, String), Option<String>> {
        // The tape first: a tree the GPU cannot encode need not open it.
        let Some(r) = &mut self.ready else {
            return Err(None);
        };
        if self.backend == Backend::Cpu {
            return Err(None);
        }
        let tape = r.tape.get_or_insert_with(|| {
            Tape::from_tree(&r.compiled.tree).map_err(|e| crate::io::chain(&e))
        });
        if let Err(e) = tape {
            return Err(Some(e.clone()));
        }
        self.gpu()?;
        let (Some(Gpu::Open(ctx)), Some(r)) = (&self.gpu, &self.ready) else {
            return Err(None);
        };
        let Some(Ok(tape)) = &r.tape else {
            return Err(None);
        };
        let s = gpu_settings(scene, &r.compiled, camera);
        ctx.render(tape, camera, &s)
            .map(|f| (f, format!("GPU ({})", ctx.adapter)))
            .map_err(|e| Some(crate::io::chain(&e)))
    }

    fn draw_request(&mut self, id: u64, req: &Request) {
        let asked = Instant::now();
        // Where the edited node was before the edit: redrawn first with where it is now.
        let before = (req.focus.as_deref()).and_then(|name| {
            let r = self.ready.as_ref().filter(|r| r.version != req.version)?;
            r.compiled.support_of(&r.scene, name)
        });
        if !self.compile(&req.scene, req.version) {
            return;
        }
        let Some(r) = &self.ready else { return };
        let latest = self.latest.clone();
        let stale = move || latest.load(Ordering::SeqCst) != id;
        let camera = |(w, h): (u32, u32)| match req.view {
            Some(o) => o.camera(w, h),
            None => crate::picture::camera(&req.scene, &r.compiled.tree, None, None, w, h).ok(),
        };
        let (Some(small), Some(full)) = (
            camera(fast_size(req.size, self.per_pixel.get(), DRAG_BUDGET)),
            camera(req.size),
        ) else {
            self.fail(req.version, "no camera can be placed for this view".into());
            return;
        };
        let handles = r.handles.clone();
        let image = |frame, camera, settled, quality, normals, tracer: &str| {
            Report::Image(Box::new(Rendered {
                frame,
                camera,
                version: req.version,
                settled,
                quality,
                latency: asked.elapsed(),
                normals,
                handles: handles.clone(),
                tracer: tracer.to_string(),
            }))
        };
        let started = Instant::now();
        let fast = draw(&req.scene, &r.compiled, &small, Quality::Fast);
        let pixels = small.width as f64 * small.height as f64;
        self.per_pixel
            .set(Some(started.elapsed().as_secs_f64() / pixels));
        let fast_normals = req
            .normals
            .then(|| frame_normal_colours(&r.compiled.tree, &fast, &small));
        self.send(image(
            fast.clone(),
            small,
            false,
            Quality::Fast,
            fast_normals,
            "CPU",
        ));
        if req.coarse || stale() {
            return;
        }
        let cpu = match self.gpu_image(&req.scene, &full) {
            Ok((frame, tracer)) => {
                if !stale() {
                    let Some(r) = &self.ready else { return };
                    let normals = req
                        .normals
                        .then(|| frame_normal_colours(&r.compiled.tree, &frame, &full));
                    self.send(image(frame, full, true, Quality::Full, normals, &tracer));
                }
                return;
            }
            Err(None) => "CPU".to_string(),
            Err(Some(why)) => format!("CPU (not the GPU: {why})"),
        };
        let Some(r) = &self.ready else { return };
        let mut normals = req
            .normals
            .then(|| vec![0u8; full.width as usize * full.height as usize * 4]);
        let mut done = 0;
        let mut sent = Instant::now();
        let first = (req.focus.as_deref())
            .and_then(|name| r.compiled.support_of(&req.scene, name))
            .map(|b| b.union(before.unwrap_or(Aabb::EMPTY)))
            .and_then(|b| rows_of(&full, &b));
        let refined = refine(
            &req.scene,
            &r.compiled,
            &full,
            &fast,
            first,
            &stale,
            &mut |f, rows| {
                if let Some(n) = &mut normals {
                    normal_colours(&r.compiled.tree, f, &full, rows.clone(), n);
                }
                done += rows.len() as u32;
                if done < f.height && sent.elapsed() >= PARTIAL_EVERY {
                    sent = Instant::now();
                    self.send(image(
                        f.clone(),
                        full,
                        false,
                        Quality::Full,
                        normals.clone(),
                        &cpu,
                    ));
                }
            },
        );
        if let Some(frame) = refined {
            self.send(image(frame, full, true, Quality::Full, normals, &cpu));
        }
    }
}

/// The editor's refinement of a view on the CPU: `fast` (its fast pass) enlarged to
/// `camera`'s size, then the full image traced over it band by band, shaded as
/// `karstic render` shades it, its edges supersampled last; the bands that meet the image
/// rows `first` (an edited node's) before the others; `band_done(frame, rows)` after each
/// band with the rows it traced, and after the supersampling with none. `None` when
/// `stop` said so before the end.
pub fn refine(
    scene: &Scene,
    compiled: &Compiled,
    camera: &Camera,
    fast: &Frame,
    first: Option<std::ops::Range<u32>>,
    stop: &(dyn Fn() -> bool + Sync),
    band_done: &mut dyn FnMut(&Frame, std::ops::Range<u32>),
) -> Option<Frame> {
    let mut frame = enlarge(fast, camera.width, camera.height);
    let settings = settings(scene, compiled, camera, Quality::Full);
    let bands = Bands {
        rows: 1,
        first,
        progress: &ProgressBar::hidden(),
        stop,
    };
    if !render_bands(
        &compiled.tree,
        camera,
        &settings,
        &mut frame,
        &bands,
        band_done,
    ) {
        return None;
    }
    // Its edges supersampled last, as `karstic render` draws them: the same picture.
    if settings.antialias {
        antialias(&compiled.tree, camera, &settings, &mut frame);
        band_done(&frame, camera.height..camera.height);
    }
    Some(frame)
}

/// The image rows (of `camera`'s image) that the box `b` covers; `None` when it reaches
/// behind the eye (then it may cover any row).
fn rows_of(camera: &Camera, b: &Aabb) -> Option<std::ops::Range<u32>> {
    if b.is_empty() {
        return None;
    }
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in b.corners() {
        let (_, y) = super::points::project(camera, p)?;
        (lo, hi) = (lo.min(y), hi.max(y));
    }
    let h = camera.height as f32;
    let (lo, hi) = (lo.clamp(0.0, h) as u32, hi.ceil().clamp(0.0, h) as u32);
    (lo < hi).then_some(lo..hi)
}

/// `frame` enlarged to `width × height` by repeating its pixels.
fn enlarge(frame: &Frame, width: u32, height: u32) -> Frame {
    let n = width as usize * height as usize;
    let (mut rgba, mut depth, mut steps) = (Vec::with_capacity(4 * n), vec![0.0; n], vec![0; n]);
    rgba.resize(4 * n, 0);
    for j in 0..height {
        let sj = (j as u64 * frame.height as u64 / height as u64) as u32;
        for i in 0..width {
            let si = (i as u64 * frame.width as u64 / width as u64) as u32;
            let (to, from) = ((j * width + i) as usize, (sj * frame.width + si) as usize);
            rgba[4 * to..4 * to + 4].copy_from_slice(&frame.rgba[4 * from..4 * from + 4]);
            depth[to] = frame.depth[from];
            steps[to] = frame.steps[from];
        }
    }
    Frame::new(width, height, rgba, depth, steps)
}

/// Writes into `out` (RGBA8, `frame`'s size) the colours `(n + 1) / 2` of the outward
/// normals of `field` at the surface points of `frame`'s rows `rows` (drawn through
/// `camera`); black where the rays missed.
pub fn normal_colours(
    field: &dyn crate::field::Field,
    frame: &Frame,
    camera: &Camera,
    rows: std::ops::Range<u32>,
    out: &mut [u8],
) {
    let w = frame.width as usize;
    let (a, b) = (rows.start as usize * w, rows.end as usize * w);
    out[4 * a..4 * b]
        .par_chunks_mut(4)
        .enumerate()
        .for_each(|(k, px)| {
            let at = a + k;
            let t = frame.depth[at];
            let c = if t.is_finite() {
                let ray = camera.pixel_ray((at % w) as u32, (at / w) as u32);
                let n = normal(field, ray.at(t));
                let q = |x: f32| ((x + 1.0) * 127.5).round().clamp(0.0, 255.0) as u8;
                [q(n.x), q(n.y), q(n.z), 255]
            } else {
                [0, 0, 0, 255]
            };
            px.copy_from_slice(&c);
        });
}

/// [`normal_colours`] of all of `frame`'s rows.
fn frame_normal_colours(
    field: &dyn crate::field::Field,
    frame: &Frame,
    camera: &Camera,
) -> Vec<u8> {
    let mut n = vec![0u8; frame.rgba.len()];
    normal_colours(field, frame, camera, 0..frame.height, &mut n);
    n
}

/// The settings of an image of `quality` of the scene through `camera`.
pub fn settings(
    scene: &Scene,
    compiled: &Compiled,
    camera: &Camera,
    quality: Quality,
) -> RenderSettings {
    let mut s = crate::picture::settings(
        scene,
        &compiled.tree,
        compiled.ground.clone(),
        camera,
        Method::Segment,
    );
    if quality == Quality::Fast {
        s.shading.shadows = false;
        s.shading.ao_radius = 0.0;
        s.shading.cave_reach = 0.0;
        s.trace.cone *= FAST_CONE;
    }
    s
}

/// The settings of the GPU viewport: [`settings`] at full quality without what the
/// shader does not draw — plants, talus and streams (`gpu::unsupported`) — so it shows
/// the ground bare.
pub fn gpu_settings(scene: &Scene, compiled: &Compiled, camera: &Camera) -> RenderSettings {
    let mut s = settings(scene, compiled, camera, Quality::Full);
    s.vegetation = None;
    s.materials.top = None;
    s
}

/// One image of the scene: with [`Quality::Full`], shaded as `karstic render` shades it.
pub fn draw(scene: &Scene, compiled: &Compiled, camera: &Camera, quality: Quality) -> Frame {
    let s = settings(scene, compiled, camera, quality);
    cpu::render(&compiled.tree, camera, &s, &ProgressBar::hidden())
}
