//! Reading and writing tree files, with errors that say where and what.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use ron::extensions::Extensions;

use super::spec::{FORMAT_VERSION, NodeSpec, Scene};

/// Errors from loading, validating, compiling or editing a tree file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The text is not a valid tree file at a position.
    #[error("{path}:{line}:{col}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// What was expected.
        message: String,
    },
    /// A node is well-formed but cannot be compiled (missing asset, bad geometry…).
    #[error("{path}: node {node}: {message}")]
    Node {
        /// The file.
        path: PathBuf,
        /// The node's name or kind.
        node: String,
        /// What went wrong.
        message: String,
    },
    /// An edit command could not be applied.
    #[error("{path}: {message}")]
    Edit {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// The RON options of tree files: `Some` may be left out, and a node's fields may be
/// written straight inside its kind, `Blend(children: [...])`.
pub fn ron_options() -> ron::Options {
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES)
}

/// A loaded tree file: the scene and where it came from.
#[derive(Clone, Debug)]
pub struct SceneFile {
    /// The parsed scene.
    pub scene: Scene,
    /// The file path.
    pub path: PathBuf,
    /// Its folder: asset paths in the scene are relative to it.
    pub base_dir: PathBuf,
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Position of the `nth` (0-based) occurrence of `key: "value"` in `text`, if found.
fn find_field(text: &str, key: &str, value: &str, nth: usize) -> Option<(usize, usize)> {
    let quoted = format!("\"{value}\"");
    let mut count = 0;
    let mut from = 0;
    while let Some(at) = text[from..].find(&quoted) {
        let pos = from + at;
        let prefix = text[..pos].trim_end();
        let prefix = prefix.strip_suffix(':').map(str::trim_end).unwrap_or("");
        if prefix.ends_with(key) {
            if count == nth {
                return Some(line_col(text, pos));
            }
            count += 1;
        }
        from = pos + quoted.len();
    }
    None
}

impl SceneError {
    fn at(path: &Path, pos: Option<(usize, usize)>, message: String) -> Self {
        let (line, col) = pos.unwrap_or((1, 1));
        SceneError::Syntax {
            path: path.to_path_buf(),
            line,
            col,
            message,
        }
    }
}

/// A node name must be a simple identifier so `NAME.PARAM` paths stay unambiguous.
fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// Parses and validates tree-file text (`path` only names it in errors).
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let scene: Scene = ron_options()
        .from_str(text)
        .map_err(|e| SceneError::Syntax {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })?;
    if scene.version != FORMAT_VERSION {
        return Err(SceneError::at(
            path,
            find_version(text),
            format!(
                "unsupported format version {} (this karstic reads version {FORMAT_VERSION})",
                scene.version
            ),
        ));
    }
    validate_names(&scene, text, path)?;
    Ok(scene)
}

/// Position of the `version:` field (not a mention of the word in a comment).
fn find_version(text: &str) -> Option<(usize, usize)> {
    text.match_indices("version")
        .find(|(at, w)| text[at + w.len()..].trim_start().starts_with(':'))
        .map(|(at, _)| line_col(text, at))
}

/// Names are valid and unique; every instance refers to an existing node and no instance
/// refers to a subtree that contains it.
fn validate_names(scene: &Scene, text: &str, path: &Path) -> Result<(), SceneError> {
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    for n in scene.all_nodes() {
        let Some(name) = n.name() else { continue };
        let nth = seen.entry(name).or_insert(0);
        let pos = find_field(text, "name", name, *nth);
        if !valid_name(name) {
            return Err(SceneError::at(
                path,
                pos,
                format!("invalid node name {name:?}: expected letters, digits, '_' or '-'"),
            ));
        }
        if *nth > 0 {
            return Err(SceneError::at(
                path,
                pos,
                format!("duplicate node name {name:?}"),
            ));
        }
        *nth += 1;
    }
    let mut instance_count: BTreeMap<&str, usize> = BTreeMap::new();
    for n in scene.all_nodes() {
        let NodeSpec::Instance(i) = n else { continue };
        let nth = instance_count.entry(&i.of).or_insert(0);
        let pos = find_field(text, "of", &i.of, *nth);
        *nth += 1;
        let Some(target) = scene.find(&i.of) else {
            let names: Vec<&str> = seen.keys().copied().collect();
            return Err(SceneError::at(
                path,
                pos,
                format!(
                    "unknown node referenced: {:?} (named nodes: {})",
                    i.of,
                    names.join(", ")
                ),
            ));
        };
        if reaches(scene, target, &i.of, &mut BTreeSet::new()) {
            return Err(SceneError::at(
                path,
                pos,
                format!(
                    "instance of {:?} is inside the node it instances (a cycle)",
                    i.of
                ),
            ));
        }
    }
    Ok(())
}

/// True when `node`'s subtree, following instances, contains an instance of `name`.
fn reaches<'a>(
    scene: &'a Scene,
    node: &'a NodeSpec,
    name: &str,
    visiting: &mut BTreeSet<&'a str>,
) -> bool {
    let mut found = false;
    node.walk(&mut |n, _| {
        if found {
            return;
        }
        if let NodeSpec::Instance(i) = n {
            if i.of == name {
                found = true;
            } else if visiting.insert(i.of.as_str())
                && let Some(t) = scene.find(&i.of)
            {
                found = reaches(scene, t, name, visiting);
            }
        }
    });
    found
}

impl Scene {
    /// The node named `name` (in `defs` or the tree).
    pub fn find(&self, name: &str) -> Option<&NodeSpec> {
        self.all_nodes()
            .into_iter()
            .find(|n| n.name() == Some(name))
    }

    /// The scene as tree-file text (canonical layout; comments are not kept).
    pub fn to_ron(&self) -> String {
        let pretty = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .indentor("    ".to_string())
            .extensions(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES);
        ron::ser::to_string_pretty(self, pretty).expect("scene types always serialize")
    }
}

/// Loads and validates a tree file.
pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        message: format!("cannot read tree file: {e}"),
    })?;
    let scene = parse_scene(&text, path)?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(SceneFile {
        scene,
        path: path.to_path_buf(),
        base_dir,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_are_one_based() {
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
        assert_eq!(
            find_field("x\n  name: \"a\", of: \"a\"", "of", "a", 0),
            Some((2, 18))
        );
    }
}
