//! Reading and writing tree files, with errors that say where and what.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use ron::extensions::Extensions;

use super::spec::{FORMAT_VERSION, NodeSpec, Scene};
use super::validate::{Locate, Problem, validate};
use crate::io::read_regular;
use crate::value::ron_options;
use crate::voxel::spec::CurveSource;

/// Errors from loading, validating, compiling or editing a tree file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read (or is not a regular file).
    #[error(transparent)]
    Read(crate::io::IoError),
    /// The file could not be written.
    #[error(transparent)]
    Write(crate::io::IoError),
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
    /// A node is well-formed but cannot be compiled (bad geometry, no terrain…).
    #[error("{path}: node {node}: {message}")]
    Node {
        /// The file.
        path: PathBuf,
        /// The node's name or kind.
        node: String,
        /// What went wrong.
        message: String,
    },
    /// A node's asset could not be made: its DEM, its curve file, its voxel pipeline.
    #[error("{path}: node {node}")]
    Asset {
        /// The file.
        path: PathBuf,
        /// The node's name or kind.
        node: String,
        /// What went wrong.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The Feature Volume asked for is not in the file (`karstic curves build --node`).
    #[error("{path}: {message}")]
    Volume {
        /// The file.
        path: PathBuf,
        /// Which volumes there are.
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

/// A scene type as tree-file text (canonical layout, the extensions of [`ron_options`]).
pub fn to_ron_text(value: &impl serde::Serialize) -> String {
    let pretty = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .indentor("    ".to_string())
        .extensions(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES);
    ron::ser::to_string_pretty(value, pretty).expect("scene types always serialize")
}

/// A scene value as one line of tree-file text, as an author writes one: no `#![enable]`
/// attributes, every struct and list on the line, whole numbers without a `.0`
/// (`Inline(tunnels: [(path: [Abs(250, 0, 5), Abs(330, 20, 5)], width: Const(24))])`).
/// The editor writes the values it builds (a curve's points) this way, so that its edits
/// read as the lines around them.
pub fn to_ron_line(value: &impl serde::Serialize) -> String {
    let config = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .depth_limit(0)
        .extensions(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES);
    let text = ron::ser::to_string_pretty(value, config).expect("scene types always serialize");
    let text = super::splice::without_attributes(&text);
    // `250.0` → `250`, outside of strings.
    let mut out = String::with_capacity(text.len());
    let mut quoted = false;
    let mut chars = text.char_indices();
    while let Some((i, c)) = chars.next() {
        out.push(c);
        match c {
            '"' if !text[..i].ends_with('\\') => quoted = !quoted,
            '0'..='9' if !quoted && text[i + 1..].starts_with(".0") => {
                let rest = &text[i + 3..];
                if !rest.starts_with(|d: char| d.is_ascii_digit() || d == 'e' || d == 'E') {
                    chars.next();
                    chars.next();
                }
            }
            _ => {}
        }
    }
    out.trim().to_string()
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
fn find_quoted(text: &str, key: &str, value: &str, nth: usize) -> Option<(usize, usize)> {
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

/// Position of the first field `key:` (not a mention of the word in a comment).
fn find_key(text: &str, key: &str) -> Option<(usize, usize)> {
    text.match_indices(key)
        .find(|(at, w)| text[at + w.len()..].trim_start().starts_with(':'))
        .map(|(at, _)| line_col(text, at))
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

/// The error of a rule the text at `path` breaks, at its position in `text`.
fn located(problem: Problem, text: &str, path: &Path) -> SceneError {
    let pos = problem.at.and_then(|at| match at {
        Locate::Quoted { key, value, nth } => find_quoted(text, key, &value, nth),
        Locate::Key(key) => find_key(text, key),
    });
    SceneError::at(path, pos, problem.message)
}

/// Parses and validates tree-file text (`path` only names it in errors). A UTF-8
/// byte-order mark before the text is skipped.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let scene: Scene = ron_options()
        .from_str(text)
        .map_err(|e| SceneError::Syntax {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: crate::value::ron_message(&e, text, "a karstic tree"),
        })?;
    if scene.version != FORMAT_VERSION {
        return Err(SceneError::at(
            path,
            find_key(text, "version"),
            format!(
                "unsupported format version {} (this karstic reads version {FORMAT_VERSION})",
                scene.version
            ),
        ));
    }
    validate(&scene).map_err(|p| located(p, text, path))?;
    Ok(scene)
}

impl Scene {
    /// The named nodes (in `defs` and the tree) by name; the first of a duplicated name.
    pub fn named(&self) -> HashMap<&str, &NodeSpec> {
        let mut named = HashMap::new();
        for n in self.all_nodes() {
            if let Some(name) = n.name() {
                named.entry(name).or_insert(n);
            }
        }
        named
    }

    /// The scene as tree-file text (canonical layout; comments are not kept).
    pub fn to_ron(&self) -> String {
        to_ron_text(self)
    }
}

impl SceneFile {
    /// The files compiling the scene reads: the tree file, its DEMs (with a PNG DEM's
    /// sidecar, an ASCII grid's `.prj`) and its curve files. A run's outputs must not be
    /// among them ([`crate::io::check_outputs`]).
    pub fn inputs(&self) -> Vec<PathBuf> {
        let mut files = vec![self.path.clone()];
        for n in self.scene.all_nodes() {
            match n {
                NodeSpec::Heightfield(h) => {
                    if let Some(source) = &h.source {
                        files.extend(crate::dem::files_read(
                            &self.base_dir.join(source),
                            &crate::dem::ReadOptions::default(),
                        ));
                    }
                }
                NodeSpec::Elevation(e) => {
                    files.extend(e.tree.sources().into_iter().flat_map(|p| {
                        crate::dem::files_read(
                            &self.base_dir.join(p),
                            &crate::dem::ReadOptions::default(),
                        )
                    }))
                }
                NodeSpec::FeatureVolume(f) => {
                    if let CurveSource::Path(p) = &f.curves {
                        files.push(self.base_dir.join(p));
                    }
                }
                _ => {}
            }
        }
        files
    }
}

/// Largest tree file read, in bytes: a tree is text written by people and tools.
pub const MAX_TREE_FILE: u64 = 1 << 30;

/// Reads a tree file's text: a regular UTF-8 file of at most [`MAX_TREE_FILE`] bytes.
pub fn read_text(path: &Path) -> Result<String, SceneError> {
    let bytes = read_regular(path, MAX_TREE_FILE).map_err(SceneError::Read)?;
    String::from_utf8(bytes).map_err(|e| {
        let (line, col) = line_col_bytes(e.as_bytes(), e.utf8_error().valid_up_to());
        SceneError::Syntax {
            path: path.to_path_buf(),
            line,
            col,
            message: "the file is not UTF-8 text".into(),
        }
    })
}

/// 1-based line and column of byte `offset` in the UTF-8 prefix `bytes[..offset]`.
fn line_col_bytes(bytes: &[u8], offset: usize) -> (usize, usize) {
    line_col(std::str::from_utf8(&bytes[..offset]).unwrap_or(""), offset)
}

/// Loads and validates a tree file.
pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
    let path = path.as_ref();
    let text = read_text(path)?;
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
    fn one_line_values_read_as_written() {
        use crate::voxel::spec::{CurveSource, FeatureSet};
        let text = "Inline(tunnels: [(path: [Abs(250, 0, 5), Abs(330.5, 20, -5)], \
                    width: Const(24), height: Keys([(0, 16), (1, 10.25)]))])";
        let set: CurveSource = crate::value::ron_options().from_str(text).unwrap();
        assert_eq!(
            to_ron_line(&set),
            text.split_whitespace().collect::<Vec<_>>().join(" ")
        );
        let back: CurveSource = crate::value::ron_options()
            .from_str(&to_ron_line(&set))
            .unwrap();
        assert_eq!(back, set);
        let named = CurveSource::Inline(FeatureSet::default());
        let empty: CurveSource = crate::value::ron_options()
            .from_str(&to_ron_line(&named))
            .unwrap();
        assert_eq!(empty, named);
    }

    #[test]
    fn positions_are_one_based() {
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
        assert_eq!(
            find_quoted("x\n  name: \"a\", of: \"a\"", "of", "a", 0),
            Some((2, 18))
        );
        assert_eq!(find_key("// version\n version: 2", "version"), Some((2, 2)));
    }
}
