//! Scriptable edits of tree files: set a parameter, add a node, remove a node.
//!
//! Every edit validates the result (parse, names, references, compile) before writing;
//! the file is replaced atomically and the previous versions kept (`FILE.bak`, then
//! `FILE.bak.1` … as [`BACKUPS`] says). Each edit changes only the text of what it
//! changes — `tree set` the value it sets, `tree add` the end of the parent's list, `tree
//! rm` the node's lines — so comments, order, layout and unset defaults stay as the author
//! wrote them; when the spliced text would not read back as exactly the edited tree, the
//! file is written in canonical layout instead.

use std::path::{Path, PathBuf};

use super::compile_scene;
use crate::io::{read_regular, write_bytes_atomic, write_bytes_atomic_like};
use crate::scene::load::{SceneError, load, parse_scene, to_ron_text};
use crate::scene::spec::{NodeSpec, Scene};
use crate::scene::splice::{SpliceError, append_element, find_named, remove_element, set_field};
use crate::scene::validate::validate;
use crate::value::ron_options;

fn edit_error(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Edit {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Applies `change` to the scene in `path`, validates, keeps a `.bak`, writes atomically.
/// What the edit would break is reported by node name (the rewritten text is not the
/// file's, so its positions would mislead). `in_text`, given the file's text, may make
/// the same change in the text itself: when its result reads back as exactly the edited
/// scene it is written, so comments, order, layout and unset defaults stay as the author
/// wrote them; otherwise the scene is written in canonical layout.
fn edit_file(
    path: &Path,
    change: impl FnOnce(&mut Scene) -> Result<(), SceneError>,
    in_text: impl FnOnce(&str) -> Option<String>,
) -> Result<(), SceneError> {
    let file = load(path)?;
    let mut scene = file.scene.clone();
    change(&mut scene)?;
    validate(&scene).map_err(|p| edit_error(path, format!("after the edit: {}", p.message)))?;
    compile_scene(&scene, path, &file.base_dir)?;
    let original = read_regular(path, crate::scene::load::MAX_TREE_FILE)
        .ok()
        .and_then(|b| String::from_utf8(b).ok());
    let kept = original
        .as_deref()
        .and_then(in_text)
        .filter(|text| parse_scene(text, path).is_ok_and(|s| s == scene));
    match kept {
        Some(text) => write_keeping_backup(path, text.as_bytes()),
        None => write_keeping_backup(path, scene.to_ron().as_bytes()),
    }
}

/// The file's text with the parameter `NAME.PARAM…` of [`set_param`] set to `value` in
/// place, when the node and its text can be found.
fn set_in_text(text: &str, target: &str, value: &str) -> Option<String> {
    let (name, param) = target.split_once('.')?;
    let keys: Vec<&str> = param.split('.').collect();
    let (start, end) = find_named(text, name)?;
    let node = set_field(&text[start..end], &keys, value).ok()?;
    Some(format!("{}{node}{}", &text[..start], &text[end..]))
}

/// Copies the file at `path` to `FILE.bak` (the earlier backups moved back a generation,
/// [`BACKUPS`] kept), then replaces it with `bytes` atomically. A
/// symbolic link is followed: the tree it names is edited (and backed up beside itself),
/// and the link stays a link.
fn write_keeping_backup(path: &Path, bytes: &[u8]) -> Result<(), SceneError> {
    let target = std::fs::canonicalize(path);
    let path = target.as_deref().unwrap_or(path);
    let original =
        read_regular(path, crate::scene::load::MAX_TREE_FILE).map_err(SceneError::Read)?;
    let backup = |k: usize| {
        let mut bak = path.as_os_str().to_owned();
        bak.push(if k == 0 {
            ".bak".to_string()
        } else {
            format!(".bak.{k}")
        });
        PathBuf::from(bak)
    };
    // The generations move back one: FILE.bak.{k} becomes FILE.bak.{k+1}, the oldest goes.
    for k in (0..BACKUPS - 1).rev() {
        let (from, to) = (backup(k), backup(k + 1));
        if std::fs::symlink_metadata(&from).is_ok_and(|m| m.is_file()) {
            std::fs::rename(&from, &to).map_err(|source| {
                SceneError::Write(crate::io::IoError::Write { path: to, source })
            })?;
        }
    }
    write_bytes_atomic_like(&backup(0), &original, path).map_err(SceneError::Write)?;
    write_bytes_atomic(path, bytes).map_err(SceneError::Write)
}

/// Generations of a tree file kept by its edits: `FILE.bak` (the latest), then
/// `FILE.bak.1` … `FILE.bak.4`.
pub const BACKUPS: usize = 5;

/// Puts back `text`, an earlier version of the tree file at `path` (the editor's undo and
/// redo), byte for byte: it is parsed and validated first, the current file is kept as
/// `FILE.bak`, and the file is replaced atomically.
pub fn restore(path: &Path, text: &str) -> Result<(), SceneError> {
    crate::scene::load::parse_scene(text, path)?;
    write_keeping_backup(path, text.as_bytes())
}

fn find_mut<'a>(node: &'a mut NodeSpec, name: &str) -> Option<&'a mut NodeSpec> {
    if node.name() == Some(name) {
        return Some(node);
    }
    node.children_mut()
        .into_iter()
        .find_map(|c| find_mut(c, name))
}

/// The node named `name` in `scene` (its `defs`, then its tree), to change in memory.
pub fn scene_find_mut<'a>(scene: &'a mut Scene, name: &str) -> Option<&'a mut NodeSpec> {
    scene
        .defs
        .iter_mut()
        .chain(std::iter::once(&mut scene.root))
        .find_map(|n| find_mut(n, name))
}

/// `karstic tree set FILE NAME.PARAM VALUE`: sets a parameter (a dotted path inside the
/// node, e.g. `shape.radius`) of the node named `NAME` to `VALUE`, written as in a tree
/// file (`3.5`, `(0, 0, 10)`, `Sphere(center: (0, 0, 0), radius: 4)`). An optional
/// parameter the node leaves out (`noise`, `base_depth`) is added.
pub fn set_param(path: &Path, target: &str, value: &str) -> Result<(), SceneError> {
    edit_file(
        path,
        |scene| set_in_scene(scene, path, target, value),
        |text| set_in_text(text, target, value),
    )
}

/// The change of [`set_param`] made to a scene in memory, without validating or writing it
/// (the editor's preview while a value is dragged); `path` only names the file in errors.
pub fn set_in_scene(
    scene: &mut Scene,
    path: &Path,
    target: &str,
    value: &str,
) -> Result<(), SceneError> {
    let (name, param) = target
        .split_once('.')
        .ok_or_else(|| edit_error(path, format!("expected NAME.PARAM, found {target:?}")))?;
    let keys: Vec<&str> = param.split('.').collect();
    let node = scene_find_mut(scene, name)
        .ok_or_else(|| edit_error(path, format!("no node named {name:?}")))?;
    let kind = node.kind();
    let no_param = |fields: &[String]| {
        edit_error(
            path,
            format!(
                "node {name:?} ({kind}) has no parameter {param:?} (it has: {})",
                fields.join(", ")
            ),
        )
    };
    let node_text = to_ron_text(&*node);
    let text = set_field(&node_text, &keys, value).map_err(|e| match e {
        SpliceError::NoField { fields, .. } => no_param(&fields),
        SpliceError::NotOneValue => edit_error(
            path,
            format!("value {value:?} for {target}: expected one value, as in a tree file"),
        ),
    })?;
    *node = ron_options().from_str(&text).map_err(|e| match e.code {
        ron::Error::NoSuchStructField {
            expected, found, ..
        } if keys.last() == Some(&found.as_str()) => {
            no_param(&expected.iter().map(|s| s.to_string()).collect::<Vec<_>>())
        }
        // A count given a fraction: RON's own words ("Expected comma") say nothing useful.
        _ if value
            .trim()
            .parse::<f64>()
            .is_ok_and(|v| v.is_finite() && v.fract() != 0.0)
            && {
                let whole = set_field(&node_text, &keys, "1").unwrap_or_default();
                ron_options().from_str::<NodeSpec>(&whole).is_ok()
            } =>
        {
            let key = keys.last().copied().unwrap_or_default();
            edit_error(
                path,
                format!("`{key}` takes a whole number, not {}", value.trim()),
            )
        }
        code => edit_error(path, format!("invalid value for {target}: {code}")),
    })?;
    Ok(())
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
    let change = |scene: &mut Scene| add_in_scene(scene, path, parent, node);
    edit_file(path, change, |text| {
        let at = find_named(text, parent)?;
        let node = node_ron.trim();
        ["children", "carves"]
            .iter()
            .find_map(|key| append_element(text, at, key, node))
    })
}

/// The change of [`add_node`] made to a scene in memory, without validating or writing it
/// (the editor's preview of a brush stroke); `path` only names the file in errors.
pub fn add_in_scene(
    scene: &mut Scene,
    path: &Path,
    parent: &str,
    node: NodeSpec,
) -> Result<(), SceneError> {
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
}

/// `karstic tree rm FILE NAME`: removes the node named `NAME` from its parent's children.
pub fn remove_node(path: &Path, name: &str) -> Result<(), SceneError> {
    let change = |scene: &mut Scene| {
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
    };
    edit_file(path, change, |text| {
        find_named(text, name).map(|at| remove_element(text, at))
    })
}
