//! The inspector: typed widgets for the parameters of the selected node, laid out from
//! the node's tree-file text. Numbers are drag values with their units, vectors rows of
//! them, enumerations combo boxes of the variants the loader accepts, names and paths
//! text; anything else is edited as RON. Every change is a `tree set` of one field.

use std::collections::HashMap;

use egui::{ComboBox, DragValue, RichText, TextEdit, Ui};

use crate::scene::NodeSpec;
use crate::scene::load::to_ron_text;
use crate::scene::splice::{list_items, named_fields, set_field};
use crate::value::ron_options;

/// Fields that hold child nodes: the outline edits those.
const CHILD_FIELDS: [&str; 5] = ["child", "children", "base", "carves", "by"];

/// What the user did to a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Change {
    /// A value being dragged: preview it, write nothing yet.
    Preview {
        /// `NAME.PARAM`.
        target: String,
        /// RON text.
        value: String,
    },
    /// A value to write (`tree set`).
    Commit {
        /// `NAME.PARAM`.
        target: String,
        /// RON text.
        value: String,
    },
}

/// The inspector's memory between frames.
#[derive(Default)]
pub struct Inspector {
    /// Text being typed or values being dragged, by target: shown instead of the file's.
    pub drafts: HashMap<String, String>,
    /// The loader's complaint about a value, by target.
    pub errors: HashMap<String, String>,
    /// The variants of enumerations, by node kind and field path.
    variants: HashMap<String, Option<Vec<String>>>,
    /// Whether the value at a field path of a node kind may be `None`.
    optional: HashMap<String, bool>,
}

/// The unit of a parameter, by its key.
fn unit(key: &str) -> &'static str {
    match key {
        "degrees" | "fov" => " °",
        "radius" | "radii" | "falloff" | "amplitude" | "wavelength" | "offset" | "width"
        | "height" | "voxel" | "blend" | "translate" | "center" | "at" | "min" | "max" | "eye"
        | "target" | "a" | "b" | "from" | "to" | "thickness" | "depth" | "cell" => " m",
        _ => "",
    }
}

/// A number as tree-file text (`3`, `2.5`).
fn number_text(v: f64) -> String {
    format!("{}", v as f32)
}

/// The numbers of a tuple of numbers `(1, 2.5, -3)`.
fn numbers(text: &str) -> Option<Vec<f64>> {
    let inner = text.strip_prefix('(')?.strip_suffix(')')?;
    let v: Option<Vec<f64>> = inner
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().ok())
        .collect();
    v.filter(|v| !v.is_empty())
}

/// Whether a value's text is a whole number as a tree file writes a count (`8`, not
/// `8.0`): its widget then shows and steps whole numbers (a count shown as `8.00` took
/// `9.5` and answered "Expected comma").
fn is_whole(text: &str) -> bool {
    let digits = text.strip_prefix('-').unwrap_or(text);
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
}

fn is_ident(text: &str) -> bool {
    !text.is_empty()
        && text.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && text.starts_with(|c: char| c.is_ascii_uppercase())
}

impl Inspector {
    /// Shows the parameters of `node` (named `name`); returns what the user changed.
    pub fn show(&mut self, ui: &mut Ui, node: &NodeSpec, name: &str) -> Vec<Change> {
        let text = to_ron_text(node);
        let mut changes = Vec::new();
        ui.heading(format!("{} {name}", node.kind()));
        if let Some((_, fields)) = named_fields(&text) {
            egui::Grid::new("params").num_columns(2).show(ui, |ui| {
                for (key, value) in fields {
                    if CHILD_FIELDS.contains(&key) {
                        continue;
                    }
                    self.field(ui, node, &text, name, &[key], value, &mut changes);
                }
            });
        }
        changes
    }

    /// The variants the loader accepts at `path` of `node`, if the value there is an
    /// enumeration: asked of the parser with a name no enumeration has.
    fn variants_of(&mut self, node: &NodeSpec, text: &str, path: &[&str]) -> Option<Vec<String>> {
        let key = format!("{}.{}", node.kind(), path.join("."));
        self.variants
            .entry(key)
            .or_insert_with(|| {
                let probe = set_field(text, path, "NoSuchVariant").ok()?;
                match ron_options().from_str::<NodeSpec>(&probe) {
                    Err(e) => match e.code {
                        ron::Error::NoSuchEnumVariant { expected, .. } => {
                            Some(expected.iter().map(|s| s.to_string()).collect())
                        }
                        _ => None,
                    },
                    Ok(_) => None,
                }
            })
            .clone()
    }

    /// Whether the value at `path` of `node` (whose text is `text`) may be `None`: asked of
    /// the parser.
    fn is_optional(&mut self, node: &NodeSpec, text: &str, path: &[&str]) -> bool {
        let key = format!("{}.{}", node.kind(), path.join("."));
        *(self.optional)
            .entry(key)
            .or_insert_with(|| accepts(text, path, "None"))
    }

    #[allow(clippy::too_many_arguments)]
    fn field(
        &mut self,
        ui: &mut Ui,
        node: &NodeSpec,
        text: &str,
        name: &str,
        path: &[&str],
        value: &str,
        changes: &mut Vec<Change>,
    ) {
        let key = path.last().copied().unwrap_or_default();
        let target = format!("{name}.{}", path.join("."));
        let shown = self.drafts.get(&target).cloned();
        let current = shown.clone().unwrap_or_else(|| value.to_string());
        let current = current.as_str();
        if let Some((variant, inner)) = named_fields(value) {
            ui.label(key);
            ui.label(RichText::new(variant).italics());
            ui.end_row();
            for (k, v) in inner {
                let mut sub = path.to_vec();
                sub.push(k);
                self.field(ui, node, text, name, &sub, v, changes);
            }
            return;
        }
        let label = ui.label(key).id;
        ui.vertical(|ui| {
            let u = unit(key);
            // (A name stays: an unnamed node cannot be addressed.)
            if key != "name" && self.is_optional(node, text, path) {
                // An option: a toggle; set, its value's widget under it.
                let mut on = current != "None";
                let toggle = ui.checkbox(&mut on, "set").labelled_by(label);
                if toggle.changed() {
                    let value = match on {
                        true => first_value(text, path),
                        false => Some("None".to_string()),
                    };
                    match value {
                        Some(value) => changes.push(Change::Commit {
                            target: target.clone(),
                            value,
                        }),
                        None => {
                            (self.errors)
                                .insert(target.clone(), format!("type a value for `{key}`"));
                        }
                    }
                }
                if !on && !self.errors.contains_key(&target) {
                    return;
                }
            }
            if is_whole(value)
                && let Ok(mut n) = current.parse::<i64>()
            {
                // A count (`iterations`, `octaves`): whole steps, written whole.
                let r = ui.add(DragValue::new(&mut n).speed(0.1).suffix(u));
                let r = r.labelled_by(label);
                number_change(&r, &target, n.to_string(), changes);
            } else if let Ok(mut v) = current.parse::<f64>() {
                let s = speed(v);
                let r = ui.add(DragValue::new(&mut v).speed(s).suffix(u));
                let r = r.labelled_by(label);
                number_change(&r, &target, number_text(v), changes);
            } else if let Some(mut vs) = numbers(current) {
                let mut rs = Vec::new();
                ui.horizontal(|ui| {
                    for v in vs.iter_mut() {
                        let s = speed(*v);
                        rs.push(
                            ui.add(DragValue::new(v).speed(s).suffix(u))
                                .labelled_by(label),
                        );
                    }
                });
                let joined = vs.iter().map(|&v| number_text(v)).collect::<Vec<_>>();
                let value = format!("({})", joined.join(", "));
                for r in &rs {
                    number_change(r, &target, value.clone(), changes);
                }
            } else if let Some(items) = list_items(current).filter(|v| !v.is_empty()) {
                self.rows(ui, label, &target, &items, changes);
            } else if current == "true" || current == "false" {
                let mut b = current == "true";
                if ui.checkbox(&mut b, "").labelled_by(label).changed() {
                    changes.push(Change::Commit {
                        target: target.clone(),
                        value: b.to_string(),
                    });
                }
            } else if is_ident(current)
                && let Some(options) = self.variants_of(node, text, path)
            {
                ComboBox::from_id_salt(&target)
                    .selected_text(current)
                    .show_ui(ui, |ui| {
                        for o in options {
                            if ui.selectable_label(o == current, &o).clicked() && o != current {
                                changes.push(Change::Commit {
                                    target: target.clone(),
                                    value: o,
                                });
                            }
                        }
                    })
                    .response
                    .labelled_by(label);
            } else {
                let mut s = shown.unwrap_or_else(|| {
                    current
                        .strip_prefix('"')
                        .and_then(|t| t.strip_suffix('"'))
                        .filter(|_| value.starts_with('"'))
                        .map_or_else(|| current.to_string(), str::to_string)
                });
                let r = ui
                    .add(TextEdit::singleline(&mut s).desired_width(220.0))
                    .labelled_by(label);
                if r.changed() {
                    self.drafts.insert(target.clone(), s.clone());
                }
                let entered = r.lost_focus() && self.drafts.contains_key(&target);
                if entered {
                    let written = if value.starts_with('"') && !s.starts_with('"') {
                        format!("{s:?}")
                    } else {
                        s
                    };
                    changes.push(Change::Commit {
                        target: target.clone(),
                        value: written,
                    });
                }
            }
            if let Some(e) = self.errors.get(&target) {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
        });
        ui.end_row();
    }
}

/// What a row's buttons do to a list.
enum RowEdit {
    /// Element `i` becomes the text.
    Set(usize, String),
    /// Element `i` trades places with the next.
    Swap(usize),
    /// Element `i` is removed.
    Remove(usize),
    /// A copy of the last element is appended.
    Add,
}

/// An element of a list as one row of text: its lines joined.
fn one_line(item: &str) -> String {
    item.lines().map(str::trim).collect::<Vec<_>>().join(" ")
}

impl Inspector {
    /// A list as rows: each element a line of text, moved up or down, removed; a copy of
    /// the last added. Each change writes the whole list (`tree set` of `target`), every
    /// element on one line.
    fn rows(
        &mut self,
        ui: &mut Ui,
        label: egui::Id,
        target: &str,
        items: &[&str],
        changes: &mut Vec<Change>,
    ) {
        let n = items.len();
        let mut edit = None;
        for (i, item) in items.iter().enumerate() {
            let draft = format!("{target}[{i}]");
            // The buttons first, so that they stay in the panel; the text takes the rest.
            ui.horizontal(|ui| {
                let button = |ui: &mut Ui, on: bool, text: &str| {
                    ui.add_enabled(on, egui::Button::new(text).small())
                        .clicked()
                };
                if button(ui, i > 0, "up") {
                    edit = Some(RowEdit::Swap(i - 1));
                }
                if button(ui, i + 1 < n, "down") {
                    edit = Some(RowEdit::Swap(i));
                }
                if button(ui, n > 1, "remove") {
                    edit = Some(RowEdit::Remove(i));
                }
                let mut s = (self.drafts.get(&draft).cloned()).unwrap_or_else(|| one_line(item));
                let width = ui.available_width().clamp(80.0, 400.0);
                let r = ui
                    .add(TextEdit::singleline(&mut s).desired_width(width))
                    .labelled_by(label);
                if r.changed() {
                    self.drafts.insert(draft.clone(), s.clone());
                }
                if r.lost_focus() && self.drafts.contains_key(&draft) {
                    edit = Some(RowEdit::Set(i, s));
                }
            });
        }
        if ui
            .button("add")
            .on_hover_text("a copy of the last row")
            .clicked()
        {
            edit = Some(RowEdit::Add);
        }
        let Some(edit) = edit else { return };
        let mut list: Vec<String> = items.iter().map(|t| one_line(t)).collect();
        match edit {
            RowEdit::Set(i, s) => list[i] = s,
            RowEdit::Swap(i) => list.swap(i, i + 1),
            RowEdit::Remove(i) => {
                list.remove(i);
            }
            RowEdit::Add => list.push(list[n - 1].clone()),
        }
        changes.push(Change::Commit {
            target: target.to_string(),
            value: format!("[{}]", list.join(", ")),
        });
    }
}

/// The values an option switched on starts from, the first the loader accepts: a number,
/// a point, a flag, a unit.
const FIRST_VALUES: [&str; 6] = ["1", "0", "(0, 0, 0)", "(0, 0)", "true", "()"];

/// The value an option at `path` of the node text `text` takes when switched on: the
/// first of [`FIRST_VALUES`] the loader accepts there (`None`: it needs typing).
fn first_value(text: &str, path: &[&str]) -> Option<String> {
    (FIRST_VALUES.iter())
        .find(|v| accepts(text, path, v))
        .map(|v| v.to_string())
}

/// Whether the loader takes the node text `text` with `value` at `path`.
fn accepts(text: &str, path: &[&str], value: &str) -> bool {
    set_field(text, path, value).is_ok_and(|t| ron_options().from_str::<NodeSpec>(&t).is_ok())
}

/// Drag speed for a value of magnitude `v`: about a hundredth of it per point.
fn speed(v: f64) -> f64 {
    (v.abs() * 0.01).max(0.01)
}

/// A number widget's change: a preview while dragged, a commit when released or typed.
fn number_change(r: &egui::Response, target: &str, value: String, changes: &mut Vec<Change>) {
    let target = target.to_string();
    if r.dragged() && r.changed() {
        changes.push(Change::Preview { target, value });
    } else if r.drag_stopped() || (r.changed() && !r.dragged()) {
        changes.push(Change::Commit { target, value });
    }
}
