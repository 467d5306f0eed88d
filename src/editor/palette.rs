//! The palette: add, remove and duplicate nodes, instance a def, and export the mesh and
//! the picture with the command line's code.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};

use egui::Ui;

use super::app::Editor;
use super::history::Edit;
use super::placement::{duplicate, fresh_name, parent_for, sphere_at};
use crate::scene::NodeSpec;

/// Exports running in the background.
#[derive(Default)]
pub struct Exports {
    running: Option<Receiver<String>>,
}

impl Exports {
    /// The message of a finished export, if one finished.
    pub fn finished(&mut self) -> Option<String> {
        let msg = self.running.as_ref()?.try_recv().ok()?;
        self.running = None;
        Some(msg)
    }

    /// Runs `work` on a thread; its message is reported when it ends.
    fn start(&mut self, ctx: &egui::Context, work: impl FnOnce() -> String + Send + 'static) {
        let (tx, rx) = channel();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let _ = tx.send(work());
            ctx.request_repaint();
        });
        self.running = Some(rx);
    }
}

/// The parent a node named `name` sits in, if it takes children.
fn parent_of<'s>(root: &'s NodeSpec, name: &str) -> Option<&'s NodeSpec> {
    let mut found = None;
    root.walk(&mut |n, _| {
        if found.is_none()
            && n.takes_children()
            && n.children().iter().any(|c| c.name() == Some(name))
        {
            found = Some(n);
        }
    });
    found
}

/// The palette's buttons.
pub fn show(ed: &mut Editor, ui: &mut Ui) {
    let Some(scene) = ed.scene().cloned() else {
        return;
    };
    let selected = ed.selected().map(str::to_string);
    let parent = parent_for(&scene, selected.as_deref());
    if ui
        .add_enabled(parent.is_some(), egui::Button::new("Add sphere"))
        .on_hover_text("a sphere primitive at the view's centre, in the selected group")
        .clicked()
        && let Some(parent) = parent.clone()
    {
        let name = fresh_name(&scene, "sphere");
        let node = sphere_at(&name, ed.view_target(), ed.place_radius);
        if ed.apply(Edit::Add { parent, node }) {
            ed.select(Some(name));
        }
    }
    if !scene.defs.is_empty() {
        egui::ComboBox::from_label("instance")
            .selected_text("of…")
            .show_ui(ui, |ui| {
                for d in scene.defs.iter().filter_map(NodeSpec::name) {
                    if ui.button(d).clicked()
                        && let Some(parent) = parent.clone()
                    {
                        let name = fresh_name(&scene, d);
                        let node = format!("Instance(name: {name:?}, of: {d:?})");
                        if ed.apply(Edit::Add { parent, node }) {
                            ed.select(Some(name));
                        }
                    }
                }
            });
    }
    let named = scene.named();
    let node = selected.as_deref().and_then(|s| named.get(s).copied());
    if ui
        .add_enabled(node.is_some(), egui::Button::new("Duplicate"))
        .clicked()
        && let (Some(node), Some(name)) = (node, selected.as_deref())
    {
        let into = parent_of(&scene.root, name)
            .and_then(NodeSpec::name)
            .map(str::to_string)
            .or(parent.clone());
        if let (Some((copy, text)), Some(into)) = (duplicate(&scene, node), into)
            && ed.apply(Edit::Add {
                parent: into,
                node: text,
            })
        {
            ed.select(Some(copy));
        }
    }
    if ui
        .add_enabled(node.is_some(), egui::Button::new("Remove"))
        .clicked()
        && let Some(name) = selected
        && ed.apply(Edit::Remove { name })
    {
        ed.select(None);
    }
    ui.separator();
    exports(ed, ui);
}

fn exports(ed: &mut Editor, ui: &mut Ui) {
    if let Some(msg) = ed.exports.finished() {
        ed.set_status(msg);
    }
    let busy = ed.exports.running.is_some();
    if busy {
        ui.spinner();
    }
    let path = ed.path().to_path_buf();
    let stem = path
        .file_stem()
        .map_or("tree".into(), |s| s.to_string_lossy().into_owned());
    let dir = path.parent().map(PathBuf::from).unwrap_or_default();
    if ui
        .add_enabled(!busy, egui::Button::new("Export mesh"))
        .on_hover_text("`karstic run`: the job's mesh and preview, into TREE_out/")
        .clicked()
    {
        let out = dir.join(format!("{stem}_out"));
        let opts = crate::job::JobOptions {
            out_dir: out.clone(),
            full: false,
            no_render: false,
            no_views: true,
            quiet: true,
            budget: crate::io::DEFAULT_MEMORY_BUDGET,
            origin: Default::default(),
            masks: false,
        };
        ed.set_status(format!("exporting into {}…", out.display()));
        ed.exports
            .start(ui.ctx(), move || match crate::job::run(&path, &opts) {
                Ok(r) => format!("wrote {}", r.mesh_path.display()),
                Err(e) => format!("export failed: {e:#}"),
            });
    }
    if ui
        .add_enabled(
            !busy && ed.shown().is_some(),
            egui::Button::new("Export picture"),
        )
        .on_hover_text("the current view at the job's image size, as `karstic render`")
        .clicked()
        && let Some(job) = ed.picture_job()
    {
        let out = dir.join(format!("{stem}_view.png"));
        ed.set_status(format!("rendering {}…", out.display()));
        ed.exports.start(ui.ctx(), move || match job(&out) {
            Ok(()) => format!("wrote {}", out.display()),
            Err(e) => format!("export failed: {e:#}"),
        });
    }
}
