//! The editor's state and its frame: toolbar, outline, inspector and viewport around the
//! tree file, which stays the truth (every edit is written, then the file read back).

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant, SystemTime};

use egui::{Key, KeyboardShortcut, Modifiers, Rect, Sense, TextureHandle, TextureOptions, Ui};

use super::brush::{self, Brush, Stroke};
use super::history::{Edit, History};
use super::inspector::{Change, Inspector};
use super::placement;
use super::points::{self, Handle};
use super::preview::{Backend, Look, Orbit, Preview, Quality, Rendered, Report, Request};
use crate::compile::edit;
use crate::render::Camera;
use crate::scene::load::read_text;
use crate::scene::{Scene, parse_scene};
use crate::voxel::spec::Point;

/// How far from a control point (points) a drag picks it.
pub const HANDLE_REACH: f32 = 8.0;

/// How the wheel scales a brush: by `exp(WHEEL_SIZE · scroll)`, scroll in points (a notch
/// of 50 points: ±10%).
pub const WHEEL_SIZE: f32 = 0.002;

/// What a click in the viewport does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tool {
    /// Nothing: the view only turns, pans and zooms.
    View,
    /// Adds an `Anchor` (holding a sphere) at the surface point clicked.
    Anchor,
    /// Adds a sphere `Primitive` centred on the surface point clicked.
    Sphere,
    /// A brush: a stroke dragged over the surface raises or carves it ([`brush`]).
    Brush(Brush),
}

/// The interactive editor of one tree file.
pub struct Editor {
    path: PathBuf,
    /// The file's text and what the loader made of it.
    text: String,
    scene: Option<Arc<Scene>>,
    load_error: Option<String>,
    stamp: Option<(SystemTime, u64)>,
    /// Counts the scenes handed to the renderer.
    version: u64,
    /// The version of the file's scene (a dragged value's preview has a newer one).
    file_version: u64,
    preview_scene: Option<(Arc<Scene>, u64)>,
    selected: Option<String>,
    history: History,
    inspector: Inspector,
    status: String,
    /// Whether the status line holds why an edit failed (cleared when another node is
    /// selected: the message is about the node left).
    failed: bool,
    /// What a click in the viewport does.
    pub tool: Tool,
    /// Radius of placed spheres, metres; offset of placed anchors above the ground.
    pub place_radius: f32,
    /// Height of placed anchors above the ground, metres.
    pub place_offset: f32,
    /// What the viewport shows of its images.
    pub look: Look,
    /// Whether the node graph is shown under the viewport.
    pub graph: bool,
    /// The control point being dragged and where it is now.
    point_drag: Option<(Handle, glam::Vec3)>,
    /// The brush stroke being dragged.
    stroke: Option<Stroke>,
    /// The node the last edit (or undo, or redo) changed: the first request of the file's
    /// new version refines its region first.
    focus: Option<String>,
    /// The texture shows the latest image in this look.
    texture_look: Option<Look>,
    preview: Preview,
    /// The context the preview thread wakes (known from the first frame on).
    wake: Arc<OnceLock<egui::Context>>,
    orbit: Option<Orbit>,
    shown: Option<Rendered>,
    texture: Option<TextureHandle>,
    render_error: Option<String>,
    last_request: Option<RequestKey>,
    viewport: Option<Rect>,
    dragging_view: bool,
    opened: Instant,
    first_image: Option<Duration>,
    /// Exports running in the background.
    pub(super) exports: super::exports::Exports,
}

/// What the last preview request asked for: the file's version, the view, the image size,
/// whether it was a coarse (dragging) request, and whether it asked for normals.
type RequestKey = (u64, Option<Orbit>, (u32, u32), bool, bool);

/// The file's modification time and length: a change means someone wrote it.
fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

impl Editor {
    /// Opens the tree file at `path`, its viewport refined on the GPU when a hardware
    /// adapter is there ([`Backend::Auto`]). A file the loader refuses still opens: its
    /// error is shown, with its line and column, until the file is fixed.
    pub fn open(path: &Path) -> Self {
        Self::open_with(path, Backend::Auto)
    }

    /// [`Editor::open`] with the viewport's refined images drawn by `backend`.
    pub fn open_with(path: &Path, backend: Backend) -> Self {
        // The render thread starts now and compiles the scene while the window opens.
        let wake: Arc<OnceLock<egui::Context>> = Arc::default();
        let woken = wake.clone();
        let preview = Preview::start(path, backend, move || {
            if let Some(ctx) = woken.get() {
                ctx.request_repaint();
            }
        });
        let mut e = Editor {
            path: path.to_path_buf(),
            text: String::new(),
            scene: None,
            load_error: None,
            stamp: None,
            version: 0,
            file_version: 0,
            preview_scene: None,
            selected: None,
            history: History::default(),
            inspector: Inspector::default(),
            status: String::new(),
            failed: false,
            tool: Tool::View,
            place_radius: 20.0,
            place_offset: 0.0,
            look: Look::Shaded,
            graph: false,
            point_drag: None,
            stroke: None,
            focus: None,
            texture_look: None,
            preview,
            wake,
            orbit: None,
            shown: None,
            texture: None,
            render_error: None,
            last_request: None,
            viewport: None,
            dragging_view: false,
            opened: Instant::now(),
            first_image: None,
            exports: Default::default(),
        };
        e.reload();
        e
    }

    /// Reads the file again.
    fn reload(&mut self) {
        self.stamp = stamp(&self.path);
        let parsed = read_text(&self.path).and_then(|t| {
            let s = parse_scene(&t, &self.path);
            self.text = t;
            s
        });
        match parsed {
            Ok(s) => {
                let s = Arc::new(s);
                self.scene = Some(s.clone());
                self.load_error = None;
                self.version += 1;
                self.file_version = self.version;
                self.preview.prepare(s, self.version);
            }
            Err(e) => self.load_error = Some(crate::io::chain(&e)),
        }
        self.preview_scene = None;
    }

    /// Reloads when the file changed outside the editor (the history is then forgotten:
    /// the file's new text is the new start).
    fn watch(&mut self) {
        if stamp(&self.path) != self.stamp {
            let before = self.text.clone();
            self.reload();
            if self.text != before {
                self.history.clear();
                self.status = "the file changed on disk: reloaded".into();
            }
        }
    }

    /// The file's text as last read.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The loader's error about the file, if it refuses it.
    pub fn load_error(&self) -> Option<&str> {
        self.load_error.as_deref()
    }

    /// Why the renderer drew nothing for the latest scene, if it failed.
    pub fn render_error(&self) -> Option<&str> {
        self.render_error.as_deref()
    }

    /// The status line: the last edit, or why it failed.
    pub fn status(&self) -> &str {
        &self.status
    }

    /// The latest image of the viewport.
    pub fn shown(&self) -> Option<&Rendered> {
        self.shown.as_ref()
    }

    /// Where the viewport was drawn, in points.
    pub fn viewport(&self) -> Option<Rect> {
        self.viewport
    }

    /// Time from opening to the first image.
    pub fn first_image(&self) -> Option<Duration> {
        self.first_image
    }

    /// The name of the selected node.
    pub fn selected(&self) -> Option<&str> {
        self.selected.as_deref()
    }

    /// True when the viewport shows the file's scene refined to full size and nothing is
    /// being dragged.
    pub fn settled(&self) -> bool {
        !self.dragging_view
            && self.point_drag.is_none()
            && self.stroke.is_none()
            && self.preview_scene.is_none()
            && self
                .shown
                .as_ref()
                .is_some_and(|s| s.settled && s.version == self.file_version)
            && self
                .last_request
                .is_some_and(|r| r.0 == self.file_version && !r.3)
    }

    /// Applies `edit` to the file (recorded for undo) and reads the file back.
    pub fn apply(&mut self, edit: Edit) -> bool {
        let command = edit.command();
        self.focus = edit.node();
        let done = self.history.apply(&self.path, edit);
        self.after(done.map(|_| Some(command)))
    }

    /// Undoes the last edit.
    pub fn undo(&mut self) -> bool {
        let r = self.history.undo(&self.path);
        self.focus = r.as_ref().ok().and_then(|e| e.as_ref()?.node());
        self.after(r.map(|e| e.map(|e| format!("undid {}", e.command()))))
    }

    /// Redoes the last undone edit.
    pub fn redo(&mut self) -> bool {
        let r = self.history.redo(&self.path);
        self.focus = r.as_ref().ok().and_then(|e| e.as_ref()?.node());
        self.after(r.map(|e| e.map(|e| format!("redid {}", e.command()))))
    }

    fn after(&mut self, r: Result<Option<String>, crate::scene::SceneError>) -> bool {
        match r {
            Ok(what) => {
                self.status = what.unwrap_or_default();
                self.failed = false;
                self.reload();
                true
            }
            Err(e) => {
                self.status = crate::io::chain(&e);
                self.failed = true;
                false
            }
        }
    }

    /// One frame of the editor.
    pub fn ui(&mut self, ui: &mut Ui) {
        let ctx = ui.ctx().clone();
        let _ = self.wake.set(ctx.clone());
        self.watch();
        self.receive(&ctx);
        self.shortcuts(&ctx);
        let before = self.selected.clone();
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar(ui));
        egui::Panel::left("outline")
            .default_size(220.0)
            .show(ui, |ui| {
                ui.heading("Outline");
                if let Some(scene) = &self.scene {
                    egui::ScrollArea::both()
                        .auto_shrink([false, false])
                        .show(ui, |ui| super::outline::show(ui, scene, &mut self.selected));
                }
            });
        egui::Panel::right("inspector")
            .default_size(340.0)
            .show(ui, |ui| self.inspector(ui));
        if self.graph {
            egui::Panel::bottom("graph")
                .resizable(true)
                .default_size(240.0)
                .show(ui, |ui| {
                    if let Some(scene) = &self.scene {
                        super::graph::show(ui, scene, &mut self.selected);
                    }
                });
        }
        egui::CentralPanel::default().show(ui, |ui| self.viewport_ui(ui));
        self.selection_changed(&before);
        // The file is watched for outside edits.
        ctx.request_repaint_after(Duration::from_millis(500));
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        let undo = KeyboardShortcut::new(Modifiers::COMMAND, Key::Z);
        let redo = KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
        let save = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
        if ctx.input_mut(|i| i.consume_shortcut(&save)) {
            // Nothing is held back: say so, where a user looks for a sign of saving.
            self.status = format!(
                "saved: every edit is written to {} when it is made",
                self.path.display()
            );
        } else if ctx.input_mut(|i| i.consume_shortcut(&redo)) {
            self.redo();
        } else if ctx.input_mut(|i| i.consume_shortcut(&undo)) {
            self.undo();
        }
    }

    fn toolbar(&mut self, ui: &mut Ui) {
        ui.horizontal_wrapped(|ui| {
            let (can_undo, can_redo) = self.history.can();
            if ui
                .add_enabled(can_undo, egui::Button::new("Undo"))
                .clicked()
            {
                self.undo();
            }
            if ui
                .add_enabled(can_redo, egui::Button::new("Redo"))
                .clicked()
            {
                self.redo();
            }
            ui.separator();
            ui.label("Click places:");
            ui.selectable_value(&mut self.tool, Tool::View, "nothing");
            ui.selectable_value(&mut self.tool, Tool::Anchor, "anchor");
            ui.selectable_value(&mut self.tool, Tool::Sphere, "sphere");
            ui.label("Brush:");
            ui.selectable_value(&mut self.tool, Tool::Brush(Brush::Raise), "raise")
                .on_hover_text("drag over the surface to add rock; the wheel sets the size");
            ui.selectable_value(&mut self.tool, Tool::Brush(Brush::Carve), "carve")
                .on_hover_text("drag over the surface to carve it; the wheel sets the size");
            ui.add(
                egui::DragValue::new(&mut self.place_radius)
                    .range(0.1..=1e5)
                    .prefix("r ")
                    .suffix(" m"),
            );
            ui.add(
                egui::DragValue::new(&mut self.place_offset)
                    .prefix("offset ")
                    .suffix(" m"),
            );
            ui.separator();
            ui.label("View:");
            ui.selectable_value(&mut self.look, Look::Shaded, "shaded");
            ui.selectable_value(&mut self.look, Look::Cost, "cost");
            ui.selectable_value(&mut self.look, Look::Normals, "normals");
            ui.toggle_value(&mut self.graph, "graph");
            ui.separator();
            self.palette(ui);
        });
        if let Some(e) = &self.load_error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        let tracer = self
            .shown
            .as_ref()
            .map_or("tracing…", |s| s.tracer.as_str());
        let line = match self.status.as_str() {
            "" => format!("viewport: {tracer}"),
            status => format!("{status} · viewport: {tracer}"),
        };
        // One row whatever the status says (a long `tree add` wrapped, and the toolbar's
        // height, hence the viewport's, swung between frames): elided, whole on hover.
        ui.add(egui::Label::new(line).truncate());
    }

    fn inspector(&mut self, ui: &mut Ui) {
        ui.heading("Inspector");
        let (Some(scene), Some(name)) = (self.scene.clone(), self.selected.clone()) else {
            ui.label("Select a named node in the outline.");
            return;
        };
        let named = scene.named();
        let Some(node) = named.get(name.as_str()) else {
            self.selected = None;
            return;
        };
        // The panel keeps its width whatever the node: its content scrolls rather than
        // widening it (a wider inspector narrowed the viewport, whose picture restarted at
        // its new size each time a node was selected).
        let changes = egui::ScrollArea::both()
            .auto_shrink([false, false])
            .show(ui, |ui| self.inspector.show(ui, node, &name))
            .inner;
        for change in changes {
            self.change(&scene, change);
        }
    }

    /// A parameter changed in the inspector.
    fn change(&mut self, scene: &Scene, change: Change) {
        match change {
            Change::Preview { target, value } => {
                let mut s = scene.clone();
                if edit::set_in_scene(&mut s, &self.path, &target, &value).is_ok() {
                    self.version += 1;
                    self.preview_scene = Some((Arc::new(s), self.version));
                }
                self.inspector.drafts.insert(target, value);
            }
            Change::Commit { target, value } => {
                let renamed = target
                    .strip_suffix(".name")
                    .is_some_and(|n| Some(n) == self.selected.as_deref());
                let new_name = value.trim_matches('"').to_string();
                if self.apply(Edit::Set {
                    target: target.clone(),
                    value,
                }) {
                    // The value's drafts, and its rows' when it is a list.
                    let rows = format!("{target}[");
                    (self.inspector.drafts).retain(|k, _| *k != target && !k.starts_with(&rows));
                    self.inspector.errors.remove(&target);
                    if renamed {
                        self.selected = Some(new_name);
                    }
                } else {
                    self.inspector.errors.insert(target, self.status.clone());
                    self.preview_scene = None;
                }
            }
        }
    }

    /// Takes the renderer's reports.
    fn receive(&mut self, ctx: &egui::Context) {
        let preview = &self.preview;
        for report in preview.poll() {
            match report {
                Report::Image(r) => {
                    if self.first_image.is_none() {
                        self.first_image = Some(self.opened.elapsed());
                    }
                    if self.orbit.is_none() {
                        // The view the scene's camera gave: asking for it again must not
                        // restart the refinement under way.
                        self.orbit = Some(Orbit::from_camera(&r.camera));
                        if let Some(last) = &mut self.last_request {
                            last.1 = self.orbit;
                        }
                    }
                    self.render_error = None;
                    self.shown = Some(*r);
                    self.texture_look = None;
                }
                Report::Failed { message, .. } => self.render_error = Some(message),
            }
        }
        if self.texture_look != Some(self.look)
            && let (Some(r), Some(colours)) = (&self.shown, self.shown_colours())
        {
            let size = [r.frame.width as usize, r.frame.height as usize];
            let image = egui::ColorImage::from_rgba_unmultiplied(size, &colours);
            match &mut self.texture {
                Some(t) => t.set(image, TextureOptions::LINEAR),
                None => {
                    self.texture = Some(ctx.load_texture("viewport", image, TextureOptions::LINEAR))
                }
            }
            self.texture_look = Some(self.look);
        }
    }

    /// The colours the viewport shows now (RGBA8, the latest image's size), in the
    /// current look: what its texture holds.
    pub fn shown_colours(&self) -> Option<Vec<u8>> {
        let r = self.shown.as_ref()?;
        Some(match (self.look, &r.normals) {
            (Look::Cost, _) => r.frame.cost_rgba(),
            (Look::Normals, Some(n)) => n.clone(),
            _ => r.frame.rgba.clone(),
        })
    }

    fn viewport_ui(&mut self, ui: &mut Ui) {
        let rect = ui.available_rect_before_wrap();
        self.viewport = Some(rect);
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, egui::Color32::from_gray(30));
        if let Some(t) = &self.texture {
            let uv = Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(t.id(), rect, uv, egui::Color32::WHITE);
        }
        if let Some(e) = &self.render_error {
            painter.text(
                rect.left_top() + egui::vec2(8.0, 8.0),
                egui::Align2::LEFT_TOP,
                e,
                egui::FontId::proportional(14.0),
                ui.visuals().error_fg_color,
            );
        }
        let dragging_point = self.drag_point(&response, rect);
        let on_handle = response
            .interact_pointer_pos()
            .and_then(|pos| self.handle_at(rect, pos));
        if let Some(h) = &on_handle {
            self.edit_points(&response, h);
        }
        let painting = !dragging_point && self.paint(ui, &response, rect, on_handle.is_some());
        self.draw_handles(&painter, rect);
        self.draw_brush(ui, &painter, rect);
        let moved = !dragging_point && !painting && self.navigate(ui, &response, rect);
        if response.clicked()
            && on_handle.is_none()
            && matches!(self.tool, Tool::Anchor | Tool::Sphere)
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.place(rect, pos);
        }
        let ppp = ui.ctx().pixels_per_point();
        let size = (
            ((rect.width() * ppp).round() as u32).max(8),
            ((rect.height() * ppp).round() as u32).max(8),
        );
        self.dragging_view = moved;
        self.request(size);
    }

    /// Where the viewport point `pos` is in the latest image, in its pixels.
    fn image_xy(&self, rect: Rect, pos: egui::Pos2) -> Option<(f32, f32)> {
        let f = &self.shown.as_ref()?.frame;
        let u = (pos - rect.min) / rect.size();
        Some((u.x * f.width as f32, u.y * f.height as f32))
    }

    /// The latest image's view at the viewport's full size: what points are projected
    /// through and pointed at with. (A fast pass is a few dozen pixels wide and its aspect
    /// rounded: its own camera misplaced points by several per cent of the view.)
    fn view_camera(&self) -> Option<Camera> {
        let r = self.shown.as_ref()?;
        let (w, h) = self
            .last_request
            .map_or((r.frame.width, r.frame.height), |k| k.2);
        if (w, h) == (r.camera.width, r.camera.height) {
            return Some(r.camera);
        }
        Orbit::from_camera(&r.camera).camera(w, h)
    }

    /// Where the world point `p` is in the viewport, in points.
    fn screen_pos(&self, rect: Rect, p: glam::Vec3) -> Option<egui::Pos2> {
        let cam = self.view_camera()?;
        let (x, y) = points::project(&cam, p)?;
        let (w, h) = (cam.width as f32, cam.height as f32);
        Some(rect.min + egui::vec2(x / w * rect.width(), y / h * rect.height()))
    }

    /// The control point within reach of the viewport point `pos`, the nearest.
    fn handle_at(&self, rect: Rect, pos: egui::Pos2) -> Option<Handle> {
        let r = self.shown.as_ref()?;
        r.handles
            .iter()
            .filter_map(|h| Some((h, self.screen_pos(rect, h.world)?.distance(pos))))
            .filter(|(_, d)| *d <= HANDLE_REACH)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(h, _)| h.clone())
    }

    /// Drags Feature Curve control points: a primary drag that starts on one moves it
    /// (along the surface for a `Ground` point, parallel to the image for an `Abs` one),
    /// and its release writes the volume's curves with the point moved, one edit. True
    /// while a point is dragged.
    fn drag_point(&mut self, r: &egui::Response, rect: Rect) -> bool {
        if r.drag_started_by(egui::PointerButton::Primary)
            && let Some(pos) = r.ctx.input(|i| i.pointer.press_origin())
            && let Some(h) = self.handle_at(rect, pos)
        {
            let at = h.world;
            self.point_drag = Some((h, at));
        }
        let Some((handle, at)) = self.point_drag.clone() else {
            return false;
        };
        let pos = r.interact_pointer_pos();
        // A `Ground` point lands where the image's tracer hit; an `Abs` one is placed
        // through the view's camera.
        let dropped = pos.and_then(|p| match handle.point {
            Point::Ground(..) => self.surface_at(rect, p),
            Point::Abs(..) => {
                let (s, cam) = (self.shown.as_ref()?, self.view_camera()?);
                let u = (p - rect.min) / rect.size();
                let (x, y) = (u.x * cam.width as f32, u.y * cam.height as f32);
                points::drop_at(&handle, &s.frame, &cam, x, y)
            }
        });
        let at = dropped.unwrap_or(at);
        if r.drag_stopped() {
            self.point_drag = None;
            if at != handle.world
                && let Some(scene) = self.scene.clone()
                && let Some(edit) = points::edit(&scene, &handle, points::moved(&handle, at))
                && self.apply(edit)
            {
                self.selected = Some(handle.volume.clone());
            }
        } else {
            // Only a moving pointer asks for a new preview (the surface a `Ground` point
            // lands on changes with the preview itself).
            if r.drag_delta() != egui::Vec2::ZERO
                && at != handle.world
                && let Some(scene) = &self.scene
                && let Some(s) = points::dragged_scene(scene, &handle, points::moved(&handle, at))
            {
                // The volume rebuilt on a coarse grid, as the point moves.
                self.version += 1;
                self.preview_scene = Some((Arc::new(s), self.version));
            }
            self.point_drag = Some((handle, at));
        }
        true
    }

    /// Inserts a point after the control point `h` on a double click, removes it on a
    /// secondary (right) click: each one edit of the volume's curves.
    fn edit_points(&mut self, r: &egui::Response, h: &Handle) {
        let Some(scene) = self.scene.clone() else {
            return;
        };
        let edit = if r.double_clicked() {
            points::inserted(&scene, h).ok_or_else(|| {
                "only curves and tunnel paths take more points: drag this one".to_string()
            })
        } else if r.secondary_clicked() {
            points::removed(&scene, h)
        } else {
            return;
        };
        match edit {
            Ok(edit) => {
                if self.apply(edit) {
                    self.selected = Some(h.volume.clone());
                }
            }
            Err(why) => {
                self.status = why;
                self.failed = true;
            }
        }
    }

    /// The surface point under the viewport point `pos`, as the latest image's tracer hit
    /// it.
    fn surface_at(&self, rect: Rect, pos: egui::Pos2) -> Option<glam::Vec3> {
        let shown = self.shown.as_ref()?;
        let (x, y) = self.image_xy(rect, pos)?;
        if x < 0.0 || y < 0.0 {
            return None;
        }
        placement::hit(&shown.frame, &shown.camera, x as u32, y as u32)
    }

    /// The brush tools: a primary drag over the surface strokes (a click dabs), the wheel
    /// over the viewport sets the size; the stroke becomes one node on release. A click on
    /// a control point (`on_handle`) does not dab. True while a stroke is dragged.
    fn paint(&mut self, ui: &Ui, r: &egui::Response, rect: Rect, on_handle: bool) -> bool {
        let Tool::Brush(brush) = self.tool else {
            self.stroke = None;
            return false;
        };
        if r.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.place_radius =
                    (self.place_radius * (scroll * WHEEL_SIZE).exp()).clamp(0.1, 1e5);
            }
        }
        let shift = ui.input(|i| i.modifiers.shift);
        let pos = r.interact_pointer_pos();
        let hit = pos.and_then(|p| self.surface_at(rect, p));
        if r.clicked() {
            if let Some(p) = hit.filter(|_| !on_handle) {
                self.finish_stroke(Stroke::new(brush, self.place_radius, p));
            }
            return false;
        }
        if r.drag_started_by(egui::PointerButton::Primary) && !shift {
            let start = r.ctx.input(|i| i.pointer.press_origin());
            self.stroke = start
                .and_then(|p| self.surface_at(rect, p))
                .or(hit)
                .map(|p| Stroke::new(brush, self.place_radius, p));
        }
        let Some(stroke) = &mut self.stroke else {
            return false;
        };
        let before = stroke.points.len();
        if let Some(p) = hit {
            stroke.extend(p);
        }
        if stroke.points.len() != before || r.drag_started() {
            self.preview_stroke();
        }
        if r.drag_stopped() {
            let stroke = self.stroke.take();
            self.finish_stroke(stroke.expect("a stroke is under way"));
        }
        true
    }

    /// Where `stroke` goes in the file's scene and what it adds: its node's name, its
    /// parent's and its text; else why it cannot go anywhere.
    fn stroke_node(&self, stroke: &Stroke) -> Result<(String, String, String), String> {
        let scene = self.scene.as_ref().ok_or("the file does not load")?;
        let (parent, energy) = brush::target(scene, self.selected.as_deref(), stroke.brush)?;
        let name = placement::fresh_name(scene, stroke.brush.stem());
        let text = stroke.node(&name, energy);
        Ok((name, parent, text))
    }

    /// Previews the stroke under way: the scene with its node added in memory, drawn in
    /// fast passes.
    fn preview_stroke(&mut self) {
        let (Some(scene), Some(stroke)) = (&self.scene, &self.stroke) else {
            return;
        };
        let Ok((_, parent, text)) = self.stroke_node(stroke) else {
            return;
        };
        let Ok(node) = crate::value::ron_options().from_str(&text) else {
            return;
        };
        let mut s = (**scene).clone();
        if edit::add_in_scene(&mut s, &self.path, &parent, node).is_ok() {
            self.version += 1;
            self.preview_scene = Some((Arc::new(s), self.version));
        }
    }

    /// Writes `stroke` to the tree as a new node, named for its brush.
    fn finish_stroke(&mut self, stroke: Stroke) {
        match self.stroke_node(&stroke) {
            Ok((name, parent, node)) => {
                if self.apply(Edit::Add { parent, node }) {
                    self.selected = Some(name);
                }
            }
            Err(why) => {
                self.status = why;
                self.failed = true;
                self.preview_scene = None;
            }
        }
    }

    /// The stroke under way, and the brush's size around the pointer.
    fn draw_brush(&self, ui: &Ui, painter: &egui::Painter, rect: Rect) {
        let Tool::Brush(brush) = self.tool else {
            return;
        };
        let colour = match brush {
            Brush::Raise => egui::Color32::from_rgb(120, 220, 120),
            Brush::Carve => egui::Color32::from_rgb(240, 120, 90),
        };
        let stroke = egui::Stroke::new(2.0, colour);
        if let Some(s) = &self.stroke {
            let line: Vec<egui::Pos2> = (s.points.iter())
                .filter_map(|p| self.screen_pos(rect, *p))
                .collect();
            painter.add(egui::Shape::line(line, stroke));
        }
        let Some(pos) = ui
            .input(|i| i.pointer.hover_pos())
            .filter(|p| rect.contains(*p))
        else {
            return;
        };
        let Some((p, cam)) = self
            .surface_at(rect, pos)
            .zip(self.shown.as_ref().map(|s| s.camera))
        else {
            return;
        };
        let edge = p + cam.basis().0 * self.place_radius;
        if let Some((a, b)) = self.screen_pos(rect, p).zip(self.screen_pos(rect, edge)) {
            painter.circle_stroke(a, a.distance(b), stroke);
        }
    }

    /// The control points over the image; the dragged one where it is now.
    fn draw_handles(&self, painter: &egui::Painter, rect: Rect) {
        let Some(r) = &self.shown else { return };
        let dragged = self.point_drag.as_ref();
        for h in r.handles.iter() {
            let moving = dragged.filter(|(d, _)| d.volume == h.volume && d.slot == h.slot);
            let world = moving.map_or(h.world, |(_, at)| *at);
            let Some(p) = self.screen_pos(rect, world) else {
                continue;
            };
            let (fill, radius) = match moving {
                Some(_) => (egui::Color32::from_rgb(255, 200, 40), 6.0),
                None if Some(h.volume.as_str()) == self.selected.as_deref() => {
                    (egui::Color32::from_rgb(255, 120, 40), 5.0)
                }
                None => (egui::Color32::from_rgb(240, 240, 240), 4.0),
            };
            painter.circle(
                p,
                radius,
                fill,
                egui::Stroke::new(1.0, egui::Color32::BLACK),
            );
        }
    }

    /// Turns (left or right drag), pans (middle, or shift and left) and zooms (wheel, or
    /// control and drag) the view, as DCC tools do; true while the view moves.
    fn navigate(&mut self, ui: &Ui, r: &egui::Response, rect: Rect) -> bool {
        let Some(orbit) = &mut self.orbit else {
            return false;
        };
        let d = r.drag_delta();
        let shift = ui.input(|i| i.modifiers.shift);
        let ctrl = ui.input(|i| i.modifiers.command);
        // A click, or a drag that paused, does not move the view.
        let mut moved = d != egui::Vec2::ZERO && r.dragged();
        if !moved {
        } else if r.dragged_by(egui::PointerButton::Middle)
            || (shift && r.dragged_by(egui::PointerButton::Primary))
        {
            orbit.pan(d.x, d.y, rect.height());
        } else if ctrl {
            orbit.dolly(d.y * 2.0);
        } else {
            orbit.turn(d.x, d.y);
        }
        // With a brush, the wheel sets its size ([`Editor::paint`]).
        if r.hovered() && !matches!(self.tool, Tool::Brush(_)) {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                orbit.dolly(scroll);
                moved = true;
            }
        }
        moved
    }

    /// Places the tool's node at the surface point under `pos`.
    fn place(&mut self, rect: Rect, pos: egui::Pos2) {
        let (Some(shown), Some(scene)) = (&self.shown, &self.scene) else {
            return;
        };
        let f = &shown.frame;
        let u = (pos - rect.min) / rect.size();
        let (i, j) = (
            (u.x * f.width as f32).floor() as u32,
            (u.y * f.height as f32).floor() as u32,
        );
        let Some(p) = placement::hit(f, &shown.camera, i, j) else {
            self.status = "nothing under the pointer to place on".into();
            return;
        };
        let Some(parent) = placement::parent_for(scene, self.selected.as_deref()) else {
            self.status = "select a Blend, Union, Intersection or Difference to add to".into();
            return;
        };
        let (name, node) = match self.tool {
            Tool::Anchor => {
                let name = placement::fresh_name(scene, "anchor");
                let node = placement::anchor_at(&name, p, self.place_offset, self.place_radius);
                (name, node)
            }
            _ => {
                let name = placement::fresh_name(scene, "sphere");
                (
                    name.clone(),
                    placement::sphere_at(&name, p, self.place_radius),
                )
            }
        };
        if self.apply(Edit::Add { parent, node }) {
            self.selected = Some(name);
        }
    }

    /// Asks the renderer for the current scene and view, when either changed.
    fn request(&mut self, size: (u32, u32)) {
        let preview = &self.preview;
        let (scene, version, coarse) = match (&self.preview_scene, &self.scene) {
            (Some((s, v)), _) => (s.clone(), *v, true),
            (None, Some(s)) => (s.clone(), self.file_version, self.dragging_view),
            (None, None) => return,
        };
        let normals = self.look == Look::Normals;
        let key = (version, self.orbit, size, coarse, normals);
        if self.last_request == Some(key) {
            return;
        }
        self.last_request = Some(key);
        preview.request(Request {
            scene,
            version,
            view: self.orbit,
            size,
            coarse,
            normals,
            // Only the picture of the edit: a later view starts from the top.
            focus: if version == self.file_version {
                self.focus.take()
            } else {
                None
            },
        });
    }

    /// The scene the viewport previews while a value, a control point or a stroke is
    /// dragged (the file's scene edited in memory, not written), and the version its
    /// images carry ([`Rendered::version`]).
    pub fn previewing(&self) -> Option<(&Scene, u64)> {
        self.preview_scene.as_ref().map(|(s, v)| (&**s, *v))
    }

    /// The scene as last read, if the loader accepted it.
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_deref()
    }

    /// Selects the node named `name`.
    pub fn select(&mut self, name: Option<String>) {
        let before = std::mem::replace(&mut self.selected, name);
        self.selection_changed(&before);
    }

    /// Clears the status line's failed edit when the selection left the node it was about.
    fn selection_changed(&mut self, before: &Option<String>) {
        if self.failed && self.selected != *before {
            self.status.clear();
            self.failed = false;
        }
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Sets the status line.
    pub fn set_status(&mut self, status: String) {
        self.status = status;
    }

    /// The point the view turns about (the origin before the first image).
    pub fn view_target(&self) -> glam::Vec3 {
        self.orbit.map_or(glam::Vec3::ZERO, |o| o.target)
    }

    /// The picture export: the current view of the file's scene at its job's image size
    /// (960 × 540 without a job), compiled and shaded as `karstic render` does, written
    /// as a PNG to the path it is given.
    pub fn picture_job(&self) -> Option<PictureJob> {
        let scene = self.scene.clone()?;
        let orbit = self.orbit?;
        let path = self.path.clone();
        Some(Box::new(move |out: &Path| {
            let (w, h) = scene.job.as_ref().map_or((960, 540), |j| j.image);
            let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
            let compiled = crate::compile::compile_scene(&scene, &path, &base)?;
            let camera = orbit
                .camera(w, h)
                .ok_or_else(|| anyhow::anyhow!("no camera for this view"))?;
            super::preview::draw(&scene, &compiled, &camera, Quality::Full).write_png(out)?;
            Ok(())
        }))
    }
}

/// A picture export to run on another thread: renders and writes the PNG it is given.
pub type PictureJob = Box<dyn FnOnce(&Path) -> anyhow::Result<()> + Send>;
