//! The outline: the tree's nodes (`defs` first), indented by depth, with their kinds;
//! clicking a named node selects it.

use egui::{RichText, Ui};

use crate::scene::{NodeSpec, Scene};

/// Shows the outline of `scene`; a click sets `selected` to the node's name.
pub fn show(ui: &mut Ui, scene: &Scene, selected: &mut Option<String>) {
    egui::ScrollArea::vertical().show(ui, |ui| {
        if !scene.defs.is_empty() {
            ui.label(RichText::new("defs").weak());
            for d in &scene.defs {
                d.walk(&mut |n, depth| row(ui, n, depth + 1, selected));
            }
            ui.label(RichText::new("tree").weak());
        }
        scene.root.walk(&mut |n, depth| row(ui, n, depth, selected));
    });
}

fn row(ui: &mut Ui, node: &NodeSpec, depth: usize, selected: &mut Option<String>) {
    ui.horizontal(|ui| {
        ui.add_space(12.0 * depth as f32);
        match node.name() {
            Some(name) => {
                let on = selected.as_deref() == Some(name);
                if ui.selectable_label(on, name).clicked() {
                    *selected = Some(name.to_string());
                }
            }
            None => {
                ui.label(RichText::new("(unnamed)").weak())
                    .on_hover_text("name a node in the file to edit it here");
            }
        }
        ui.label(RichText::new(node.kind()).weak().small());
    });
}
