//! `karstic edit`: the interactive editor of a tree file (egui, on eframe's wgpu renderer).
//!
//! A thin interface over the library: the file is loaded and validated by
//! [`crate::scene`], every edit is one of `karstic tree set/add/rm`'s operations
//! ([`crate::compile::edit`]) written to the file at once (validated, atomically, the
//! previous version kept as `.bak`), and the viewport is the CPU tracer
//! ([`crate::render::cpu`]) on a background thread, its refined images the wgpu tracer's
//! ([`crate::render::gpu`]) on a hardware adapter or when asked ([`preview::Backend`]).
//!
//! * [`app`]: the editor's state and frame; undo/redo; reloading on outside edits.
//! * [`history`]: edits as `tree` operations, undo byte for byte.
//! * [`outline`] and [`inspector`]: the tree and the selected node's typed parameters;
//!   [`graph`]: the same tree as a node graph (toggled from the toolbar), in sync with the
//!   outline.
//! * [`preview`]: the orbit camera and the progressive background renderer (fast pass,
//!   then the full image band by band; cost and normal views).
//! * [`placement`]: the surface point under a pixel, and the nodes placed there.
//! * [`points`]: Feature Curve control points shown, dragged, inserted and removed in the
//!   viewport.
//! * [`brush`]: sculpting strokes that raise or carve the surface, each a new node.
//! * [`palette`]: add, remove, duplicate, instance; mesh and picture exports, run in the
//!   background ([`exports`]).

pub mod app;
pub mod brush;
pub mod exports;
pub mod graph;
pub mod history;
pub mod inspector;
pub mod outline;
pub mod palette;
pub mod placement;
pub mod points;
pub mod preview;

use std::path::Path;
use std::time::{Duration, Instant};

pub use app::{Editor, Tool};
pub use history::{Edit, History};
pub use preview::Backend;

/// Opens the editor's window on the tree file at `path` (with the node named `select`
/// selected, the node graph shown if `graph`, the viewport refined by `backend`) until it
/// is closed.
pub fn run_window(
    path: &Path,
    select: Option<&str>,
    graph: bool,
    backend: Backend,
) -> anyhow::Result<()> {
    let mut editor = Editor::open_with(path, backend);
    editor.select(select.map(str::to_string));
    editor.graph = graph;
    let title = format!("karstic edit {}", path.display());
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_inner_size([1400.0, 820.0]),
        ..Default::default()
    };
    eframe::run_native(
        &title,
        options,
        Box::new(|_| Ok(Box::new(Window(editor)) as Box<dyn eframe::App>)),
    )
    .map_err(|e| anyhow::anyhow!("the editor's window: {e}"))
}

/// The editor in an eframe window.
struct Window(Editor);

impl eframe::App for Window {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.0.ui(ui);
    }
}

/// How to draw the editor headless: its window's size, the node selected, whether the
/// node graph shows, the viewport's [`Backend`], and the longest wait for the viewport to
/// settle.
#[derive(Clone, Copy, Debug)]
pub struct Headless<'a> {
    /// Window size, pixels.
    pub size: (u32, u32),
    /// The name of the node selected.
    pub select: Option<&'a str>,
    /// Whether the node graph is shown under the viewport.
    pub graph: bool,
    /// The tracer of the viewport's refined images.
    pub backend: Backend,
    /// The longest wait for the viewport to settle.
    pub timeout: Duration,
    /// The most memory the window's pictures may take, in bytes ([`SCREEN_BYTES_PER_PIXEL`]).
    pub budget: u64,
}

/// Bytes a pixel of the headless window takes at most: the viewport's frame (the
/// renderer's [`crate::render::image::BYTES_PER_PIXEL`]) and three RGBA copies (the GPU's
/// render target, its read-back, the image written).
pub const SCREEN_BYTES_PER_PIXEL: u64 = crate::render::image::BYTES_PER_PIXEL + 3 * 4;

/// The editor drawn headless (egui_kittest on a wgpu adapter, software ones included) on
/// the tree file at `path` as `how` says, stepped until the viewport has settled (the
/// full-size image of the file's scene).
pub fn headless(
    path: &Path,
    how: &Headless<'_>,
) -> anyhow::Result<egui_kittest::Harness<'static, Editor>> {
    let (width, height) = how.size;
    crate::io::check_budget(
        format!("a {width} × {height} editor window"),
        u64::from(width) * u64::from(height) * SCREEN_BYTES_PER_PIXEL,
        how.budget,
    )?;
    let mut editor = Editor::open_with(path, how.backend);
    if let Some(name) = how.select {
        anyhow::ensure!(
            editor.scene().is_some_and(|s| s.named().contains_key(name)),
            "{}: no node named {name:?}",
            path.display()
        );
        editor.select(Some(name.to_string()));
    }
    editor.graph = how.graph;
    let mut harness = egui_kittest::Harness::builder()
        .with_size(egui::vec2(width as f32, height as f32))
        .wgpu()
        .build_ui_state(|ui, e: &mut Editor| e.ui(ui), editor);
    settle(&mut harness, how.timeout)?;
    Ok(harness)
}

/// Steps `harness` until its editor's viewport has settled, at most `timeout`.
pub fn settle(
    harness: &mut egui_kittest::Harness<'_, Editor>,
    timeout: Duration,
) -> anyhow::Result<()> {
    let start = Instant::now();
    loop {
        harness.step();
        if harness.state().settled() {
            harness.step();
            return Ok(());
        }
        if let Some(e) = harness.state().load_error() {
            anyhow::bail!("{e}");
        }
        if start.elapsed() >= timeout {
            let e = harness.state();
            anyhow::bail!(
                "the viewport did not settle within {:.0} s (status: {:?}; renderer: {:?})",
                timeout.as_secs_f64(),
                e.status(),
                e.render_error().unwrap_or("no error"),
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// What `karstic edit --screenshot` measured.
#[derive(Clone, Copy, Debug)]
pub struct Timings {
    /// From opening to the first image.
    pub first: Duration,
    /// From opening to the settled image.
    pub settled: Duration,
    /// The viewport's image size, pixels.
    pub size: (u32, u32),
}

/// `karstic edit TREE --screenshot OUT`: the editor's first settled frame as a PNG, and
/// how long it took.
pub fn screenshot(path: &Path, out: &Path, how: &Headless<'_>) -> anyhow::Result<Timings> {
    let start = Instant::now();
    let mut harness = headless(path, how)?;
    let settled = start.elapsed();
    let first = harness.state().first_image().unwrap_or(settled);
    let size = harness
        .state()
        .shown()
        .map_or((0, 0), |s| (s.frame.width, s.frame.height));
    let image = harness
        .render()
        .map_err(|e| anyhow::anyhow!("rendering the editor: {e}"))?;
    let mut png = Vec::new();
    image::DynamicImage::ImageRgba8(image)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    crate::io::write_bytes_atomic(out, &png)?;
    Ok(Timings {
        first,
        settled,
        size,
    })
}
