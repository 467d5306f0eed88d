//! The viewport's renderer: the CPU tracer on a background thread, so the interface never
//! waits for it. Each request is drawn coarse first (a quarter of the size) and, unless
//! it is a drag's preview, refined to half and full size; a newer request abandons the
//! refinement of an older one.

use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::time::{Duration, Instant};

use glam::Vec3;
use indicatif::ProgressBar;

use crate::render::cpu::scene_camera;
use crate::render::{Camera, Frame, Method, RenderSettings, cpu};
use crate::scene::{Compiled, Scene, compile_scene};

/// Divisors of the image size drawn in turn: coarse, then refined.
const STAGES: [u32; 3] = [4, 2, 1];

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
    /// Only the coarse stage (while a value or the view is being dragged).
    pub coarse: bool,
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
    /// The last stage of its request: nothing more will come for it.
    pub settled: bool,
    /// Time from the request to this image.
    pub latency: Duration,
}

/// What the renderer reports.
#[derive(Debug)]
pub enum Report {
    /// An image.
    Image(Rendered),
    /// The scene could not be compiled, or no camera placed.
    Failed {
        /// Of which scene version.
        version: u64,
        /// Why.
        message: String,
    },
}

/// The background renderer.
pub struct Preview {
    requests: Sender<Request>,
    reports: Receiver<Report>,
}

impl Preview {
    /// Starts the render thread for scenes of the tree file at `path` (asset paths are
    /// relative to its folder); `wake` is called after each report (a repaint request).
    pub fn start(path: &Path, wake: impl Fn() + Send + 'static) -> Self {
        let (requests, incoming) = channel::<Request>();
        let (outgoing, reports) = channel();
        let path = path.to_path_buf();
        std::thread::Builder::new()
            .name("karstic-preview".into())
            .spawn(move || serve(&path, &incoming, &outgoing, &wake))
            .expect("spawning the preview thread");
        Preview { requests, reports }
    }

    /// Asks for an image; older requests still queued are dropped.
    pub fn request(&self, request: Request) {
        // The thread ends only with this handle, so the send cannot fail while it lives.
        let _ = self.requests.send(request);
    }

    /// The reports that arrived since the last call.
    pub fn poll(&self) -> Vec<Report> {
        self.reports.try_iter().collect()
    }
}

/// The scene compiled for a version.
struct Ready {
    version: u64,
    compiled: Compiled,
}

fn serve(path: &Path, incoming: &Receiver<Request>, out: &Sender<Report>, wake: &dyn Fn()) {
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut ready: Option<Ready> = None;
    let mut pending: Option<Request> = None;
    loop {
        let Some(mut req) = pending.take().or_else(|| incoming.recv().ok()) else {
            return;
        };
        while let Ok(newer) = incoming.try_recv() {
            req = newer;
        }
        let asked = Instant::now();
        if ready.as_ref().map(|r| r.version) != Some(req.version) {
            ready = None;
            match compile_scene(&req.scene, path, &base) {
                Ok(compiled) => {
                    ready = Some(Ready {
                        version: req.version,
                        compiled,
                    })
                }
                Err(e) => {
                    let message = crate::io::chain(&e);
                    let _ = out.send(Report::Failed {
                        version: req.version,
                        message,
                    });
                    wake();
                    continue;
                }
            }
        }
        let Some(r) = &ready else { continue };
        let stages: &[u32] = if req.coarse { &STAGES[..1] } else { &STAGES };
        for (k, div) in stages.iter().enumerate() {
            let (w, h) = ((req.size.0 / div).max(1), (req.size.1 / div).max(1));
            let camera = match req.view {
                Some(o) => o.camera(w, h),
                None => scene_camera(&req.scene, &r.compiled.tree, None, None, w, h).ok(),
            };
            let Some(camera) = camera else {
                let _ = out.send(Report::Failed {
                    version: req.version,
                    message: "no camera can be placed for this view".into(),
                });
                wake();
                break;
            };
            let frame = draw(&req.scene, &r.compiled, &camera);
            let settled = k + 1 == stages.len();
            let _ = out.send(Report::Image(Rendered {
                frame,
                camera,
                version: req.version,
                settled,
                latency: asked.elapsed(),
            }));
            wake();
            match incoming.try_recv() {
                Ok(newer) => {
                    pending = Some(newer);
                    break;
                }
                Err(TryRecvError::Disconnected) => return,
                Err(TryRecvError::Empty) => {}
            }
        }
    }
}

/// One image of the scene, shaded as `karstic render` shades it.
pub fn draw(scene: &Scene, compiled: &Compiled, camera: &Camera) -> Frame {
    let settings = RenderSettings::for_tree(
        scene,
        &compiled.tree,
        compiled.ground.clone(),
        camera,
        Method::Segment,
    );
    cpu::render(&compiled.tree, camera, &settings, &ProgressBar::hidden())
}
