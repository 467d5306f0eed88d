//! Scriptable edits of tree files: set a parameter, add a node, remove a node.
//!
//! Every edit validates the result (parse, names, references, compile) before writing;
//! the file is replaced atomically and the previous version kept as `FILE.bak`. The file
//! is written in canonical layout, so comments are not kept (they stay in the `.bak`).

use std::path::{Path, PathBuf};

use serde_json::Value as Json;

use super::compile::compile_scene;
use super::load::{SceneError, load, parse_scene, ron_options};
use super::spec::{NodeSpec, Scene};
use crate::io::write_bytes_atomic;

fn edit_error(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Edit {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Applies `change` to the scene in `path`, validates, keeps a `.bak`, writes atomically.
fn edit_file(
    path: &Path,
    change: impl FnOnce(&mut Scene) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let file = load(path)?;
    let mut scene = file.scene.clone();
    change(&mut scene)?;
    let text = scene.to_ron();
    // Validate exactly what will be written.
    let reparsed = parse_scene(&text, path)?;
    compile_scene(&reparsed, path, &file.base_dir)?;
    let io = |e: crate::io::IoError| edit_error(path, e.to_string());
    let original = std::fs::read(path).map_err(|e| edit_error(path, e.to_string()))?;
    let mut bak = path.as_os_str().to_owned();
    bak.push(".bak");
    write_bytes_atomic(&PathBuf::from(bak), &original).map_err(io)?;
    write_bytes_atomic(path, text.as_bytes()).map_err(io)
}

fn find_mut<'a>(node: &'a mut NodeSpec, name: &str) -> Option<&'a mut NodeSpec> {
    if node.name() == Some(name) {
        return Some(node);
    }
    node.children_mut()
        .into_iter()
        .find_map(|c| find_mut(c, name))
}

fn scene_find_mut<'a>(scene: &'a mut Scene, name: &str) -> Option<&'a mut NodeSpec> {
    scene
        .defs
        .iter_mut()
        .chain(std::iter::once(&mut scene.root))
        .find_map(|n| find_mut(n, name))
}

fn parse_value(path: &Path, text: &str) -> Result<Json, SceneError> {
    let v: ron::Value = ron_options()
        .from_str(text)
        .map_err(|e| edit_error(path, format!("value {text:?} is not valid RON: {}", e.code)))?;
    serde_json::to_value(v).map_err(|e| edit_error(path, format!("value {text:?}: {e}")))
}

/// `karstic tree set FILE NAME.PARAM VALUE`: sets a parameter (a dotted path inside the
/// node, e.g. `shape.radius`) of the node named `NAME` to the RON value `VALUE`.
pub fn set_param(path: &Path, target: &str, value: &str) -> Result<(), SceneError> {
    let (name, param) = target
        .split_once('.')
        .ok_or_else(|| edit_error(path, format!("expected NAME.PARAM, found {target:?}")))?;
    let new_value = parse_value(path, value)?;
    edit_file(path, |scene| {
        let node = scene_find_mut(scene, name)
            .ok_or_else(|| edit_error(path, format!("no node named {name:?}")))?;
        let mut json = serde_json::to_value(&*node).map_err(|e| edit_error(path, e.to_string()))?;
        let kind = node.kind();
        let mut slot = json
            .get_mut(kind)
            .ok_or_else(|| edit_error(path, format!("node {name:?} has no parameters")))?;
        for key in param.split('.') {
            let fields = match &*slot {
                Json::Object(m) => m.keys().cloned().collect::<Vec<_>>().join(", "),
                _ => String::new(),
            };
            // Walk into enum-tagged values ({"Sphere": {...}}) transparently.
            if let Json::Object(m) = &*slot
                && m.len() == 1
                && !m.contains_key(key)
                && let Some(inner) = m.values().next()
                && inner.get(key).is_some()
            {
                slot = slot.as_object_mut().unwrap().values_mut().next().unwrap();
            }
            slot = slot.get_mut(key).ok_or_else(|| {
                edit_error(
                    path,
                    format!("node {name:?} ({kind}) has no parameter {param:?} (it has: {fields})"),
                )
            })?;
        }
        *slot = new_value;
        *node = serde_json::from_value(json)
            .map_err(|e| edit_error(path, format!("invalid value for {name}.{param}: {e}")))?;
        Ok(())
    })
}

/// `karstic tree add FILE PARENT NODE_RON`: appends a node to the children (the carves of
/// a difference) of the node named `PARENT`.
pub fn add_node(path: &Path, parent: &str, node_ron: &str) -> Result<(), SceneError> {
    let node: NodeSpec = ron_options()
        .from_str(node_ron)
        .map_err(|e| SceneError::Syntax {
            path: PathBuf::from("<node>"),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })?;
    edit_file(path, |scene| {
        let p = scene_find_mut(scene, parent)
            .ok_or_else(|| edit_error(path, format!("no node named {parent:?}")))?;
        let kind = p.kind();
        p.child_list_mut()
            .ok_or_else(|| {
                edit_error(
                    path,
                    format!("node {parent:?} ({kind}) cannot take more children"),
                )
            })?
            .push(node);
        Ok(())
    })
}

/// `karstic tree rm FILE NAME`: removes the node named `NAME` from its parent's children.
pub fn remove_node(path: &Path, name: &str) -> Result<(), SceneError> {
    edit_file(path, |scene| {
        if scene.root.name() == Some(name) {
            return Err(edit_error(
                path,
                format!("{name:?} is the root and cannot be removed"),
            ));
        }
        if let Some(at) = scene.defs.iter().position(|d| d.name() == Some(name)) {
            scene.defs.remove(at);
            return Ok(());
        }
        fn rec(n: &mut NodeSpec, name: &str) -> Result<bool, String> {
            if let Some(list) = n.child_list_mut()
                && let Some(at) = list.iter().position(|c| c.name() == Some(name))
            {
                list.remove(at);
                return Ok(true);
            }
            let kind = n.kind();
            for c in n.children_mut() {
                if c.name() == Some(name) {
                    return Err(format!(
                        "{name:?} is the only required child of a {kind} and cannot be removed"
                    ));
                }
                if rec(c, name)? {
                    return Ok(true);
                }
            }
            Ok(false)
        }
        let removed = scene
            .defs
            .iter_mut()
            .chain(std::iter::once(&mut scene.root))
            .try_fold(false, |done, n| if done { Ok(true) } else { rec(n, name) })
            .map_err(|m| edit_error(path, m))?;
        if removed {
            Ok(())
        } else {
            Err(edit_error(path, format!("no node named {name:?}")))
        }
    })
}
