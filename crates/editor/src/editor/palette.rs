//! The palette: add, remove and duplicate nodes, instance a def, and export the mesh and
//! the picture with the command line's code.

use std::path::PathBuf;

use egui::Ui;

use super::app::Editor;
use super::history::Edit;
use super::placement::{duplicate, fresh_name, parent_for, sphere_at};
use crate::scene::NodeSpec;

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

impl Editor {
    /// The palette's buttons.
    pub(super) fn palette(&mut self, ui: &mut Ui) {
        let Some(scene) = self.scene().cloned() else {
            return;
        };
        let selected = self.selected().map(str::to_string);
        let parent = parent_for(&scene, selected.as_deref());
        if ui
            .add_enabled(parent.is_some(), egui::Button::new("Add sphere"))
            .on_hover_text("a sphere primitive at the view's centre, in the selected group")
            .clicked()
            && let Some(parent) = parent.clone()
        {
            let name = fresh_name(&scene, "sphere");
            let node = sphere_at(&name, self.view_target(), self.place_radius);
            if self.apply(Edit::Add { parent, node }) {
                self.select(Some(name));
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
                            if self.apply(Edit::Add { parent, node }) {
                                self.select(Some(name));
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
                && self.apply(Edit::Add {
                    parent: into,
                    node: text,
                })
            {
                self.select(Some(copy));
            }
        }
        if ui
            .add_enabled(node.is_some(), egui::Button::new("Remove"))
            .clicked()
            && let Some(name) = selected
            && self.apply(Edit::Remove { name })
        {
            self.select(None);
        }
        ui.separator();
        self.export_buttons(ui);
    }

    fn export_buttons(&mut self, ui: &mut Ui) {
        if let Some(msg) = self.exports.finished() {
            self.set_status(msg);
        }
        let busy = self.exports.running.is_some();
        if busy {
            ui.spinner();
        }
        let path = self.path().to_path_buf();
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
            self.set_status(format!("exporting into {}…", out.display()));
            self.exports
                .start(ui.ctx(), move || match crate::job::run(&path, &opts) {
                    Ok(r) => format!("wrote {}", r.mesh_path.display()),
                    Err(e) => format!("export failed: {e:#}"),
                });
        }
        if ui
            .add_enabled(
                !busy && self.shown().is_some(),
                egui::Button::new("Export picture"),
            )
            .on_hover_text("the current view at the job's image size, as `karstic render`")
            .clicked()
            && let Some(job) = self.picture_job()
        {
            let out = dir.join(format!("{stem}_view.png"));
            self.set_status(format!("rendering {}…", out.display()));
            self.exports.start(ui.ctx(), move || match job(&out) {
                Ok(()) => format!("wrote {}", out.display()),
                Err(e) => format!("export failed: {e:#}"),
            });
        }
    }
}
