//! The editor's history: every edit is one of `karstic tree`'s operations (`set`, `add`,
//! `rm`) applied to the file, which stays the truth. Undo puts back the file's text from
//! before the edit byte for byte; redo applies the operation again.

use std::path::Path;

use crate::compile::edit;
use crate::scene::SceneError;
use crate::scene::load::read_text;

/// One edit of a tree file, as `karstic tree set/add/rm` would make it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Edit {
    /// `tree set FILE TARGET VALUE`: `TARGET` is `NAME.PARAM`, `VALUE` RON text.
    Set {
        /// `NAME.PARAM`, e.g. `boulder.shape.radius`.
        target: String,
        /// The value as written in a tree file.
        value: String,
    },
    /// `tree add FILE PARENT NODE`: a node (RON text) appended to `PARENT`'s children.
    Add {
        /// The parent's name.
        parent: String,
        /// The node, in RON.
        node: String,
    },
    /// `tree rm FILE NAME`.
    Remove {
        /// The node's name.
        name: String,
    },
}

impl Edit {
    /// Applies the edit to the file at `path` through [`crate::compile::edit`]: validated,
    /// the previous file kept as `.bak`, written atomically.
    pub fn apply(&self, path: &Path) -> Result<(), SceneError> {
        match self {
            Edit::Set { target, value } => edit::set_param(path, target, value),
            Edit::Add { parent, node } => edit::add_node(path, parent, node),
            Edit::Remove { name } => edit::remove_node(path, name),
        }
    }

    /// The node it changes, by name: the one set, the one added (its parent when the
    /// node has no name); none for a removal (the node is gone).
    pub fn node(&self) -> Option<String> {
        match self {
            Edit::Set { target, .. } => target.split_once('.').map(|(n, _)| n.to_string()),
            Edit::Add { parent, node } => Some(
                (crate::value::ron_options()
                    .from_str::<crate::scene::NodeSpec>(node)
                    .ok())
                .and_then(|n| n.name().map(str::to_string))
                .unwrap_or_else(|| parent.clone()),
            ),
            Edit::Remove { .. } => None,
        }
    }

    /// The edit as the command line that makes it.
    pub fn command(&self) -> String {
        match self {
            Edit::Set { target, value } => format!("tree set {target} {value}"),
            Edit::Add { parent, node } => format!("tree add {parent} {node}"),
            Edit::Remove { name } => format!("tree rm {name}"),
        }
    }
}

/// An applied edit and the file's text before it.
#[derive(Clone, Debug)]
struct Step {
    edit: Edit,
    before: String,
}

/// Applied and undone edits of one file.
#[derive(Clone, Debug, Default)]
pub struct History {
    done: Vec<Step>,
    undone: Vec<Edit>,
}

impl History {
    /// Applies `edit` to the file at `path` and records it; a failed edit writes nothing
    /// and records nothing.
    pub fn apply(&mut self, path: &Path, edit: Edit) -> Result<(), SceneError> {
        let before = read_text(path)?;
        edit.apply(path)?;
        self.done.push(Step { edit, before });
        self.undone.clear();
        Ok(())
    }

    /// Puts back the file as it was before the last edit; `Ok(None)` when there is none.
    pub fn undo(&mut self, path: &Path) -> Result<Option<Edit>, SceneError> {
        let Some(step) = self.done.pop() else {
            return Ok(None);
        };
        if let Err(e) = edit::restore(path, &step.before) {
            self.done.push(step);
            return Err(e);
        }
        self.undone.push(step.edit.clone());
        Ok(Some(step.edit))
    }

    /// Applies the last undone edit again; `Ok(None)` when there is none.
    pub fn redo(&mut self, path: &Path) -> Result<Option<Edit>, SceneError> {
        let Some(edit) = self.undone.pop() else {
            return Ok(None);
        };
        let before = read_text(path)?;
        if let Err(e) = edit.apply(path) {
            self.undone.push(edit);
            return Err(e);
        }
        self.done.push(Step {
            edit: edit.clone(),
            before,
        });
        Ok(Some(edit))
    }

    /// Whether there is an edit to undo, and one to redo.
    pub fn can(&self) -> (bool, bool) {
        (!self.done.is_empty(), !self.undone.is_empty())
    }

    /// Forgets every edit (the file changed outside the editor: its text is the new start).
    pub fn clear(&mut self) {
        self.done.clear();
        self.undone.clear();
    }
}
