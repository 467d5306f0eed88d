//! Files that hold Feature Volumes (`karstic curves build`): a tree file with
//! `FeatureVolume` nodes, or a RON file holding one bare `FeatureVolume(..)`.

use std::path::{Path, PathBuf};

use super::load::{SceneError, SceneFile, parse_scene, read_text};
use crate::voxel::FeatureVolumeSpec;
use crate::voxel::SField;
use crate::voxel::spec::{BuildOptions, CurveSource, parse_ron};

/// A loaded Feature Volume file.
#[derive(Clone, Debug)]
pub enum VolumeFile {
    /// A bare `FeatureVolume(..)`.
    Bare {
        /// The volume (boxed, like the tree file: both are large).
        spec: Box<FeatureVolumeSpec>,
        /// The file.
        path: PathBuf,
        /// Its folder: curve files are relative to it.
        base_dir: PathBuf,
    },
    /// A tree file (boxed: far larger than a bare volume).
    Tree(Box<SceneFile>),
}

/// True when the first token of the RON text (after comments) is `FeatureVolume`.
pub fn is_bare_volume(text: &str) -> bool {
    let mut rest = text.trim_start_matches('\u{feff}').trim_start();
    loop {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, r)| r).trim_start();
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |(_, r)| r).trim_start();
        } else {
            return rest.starts_with("FeatureVolume");
        }
    }
}

impl VolumeFile {
    /// Reads `path` as a bare volume or as a tree file, whichever it holds.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = read_text(path)?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        if is_bare_volume(&text) {
            let spec = parse_ron(&text, path).map_err(|e| SceneError::Asset {
                path: path.to_path_buf(),
                node: "FeatureVolume".into(),
                source: Box::new(e),
            })?;
            return Ok(VolumeFile::Bare {
                spec: Box::new(spec),
                path: path.to_path_buf(),
                base_dir,
            });
        }
        Ok(VolumeFile::Tree(Box::new(SceneFile {
            scene: parse_scene(&text, path)?,
            path: path.to_path_buf(),
            base_dir,
        })))
    }

    /// The file.
    pub fn path(&self) -> &Path {
        match self {
            VolumeFile::Bare { path, .. } => path,
            VolumeFile::Tree(f) => &f.path,
        }
    }

    /// The files building its volumes reads: the file itself, its curve files and, in a
    /// tree, its DEMs ([`SceneFile::inputs`]).
    pub fn inputs(&self) -> Vec<PathBuf> {
        match self {
            VolumeFile::Bare {
                spec,
                path,
                base_dir,
            } => {
                let mut files = vec![path.clone()];
                if let CurveSource::Path(p) = &spec.curves {
                    files.push(base_dir.join(p));
                }
                files
            }
            VolumeFile::Tree(f) => f.inputs(),
        }
    }

    /// The folder curve files are relative to.
    pub fn base_dir(&self) -> &Path {
        match self {
            VolumeFile::Bare { base_dir, .. } => base_dir,
            VolumeFile::Tree(f) => &f.base_dir,
        }
    }

    /// The volume named `node`, or the file's only one. A bare file has no names: `node`
    /// is refused there.
    pub fn pick(&self, node: Option<&str>) -> Result<&FeatureVolumeSpec, SceneError> {
        let missing = |message: String| SceneError::Volume {
            path: self.path().to_path_buf(),
            message,
        };
        let file = match (self, node) {
            (VolumeFile::Bare { spec, .. }, None) => return Ok(&**spec),
            (VolumeFile::Bare { .. }, Some(_)) => {
                return Err(missing(
                    "a bare FeatureVolume file has one volume: --node applies to tree files".into(),
                ));
            }
            (VolumeFile::Tree(f), _) => f,
        };
        let all = file.feature_volumes();
        let names = || {
            all.iter()
                .map(|f| f.name.as_deref().unwrap_or("<unnamed>"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match (node, all.as_slice()) {
            (_, []) => Err(missing("the tree has no FeatureVolume node".into())),
            (None, [one]) => Ok(one),
            (None, _) => Err(missing(format!(
                "the tree has several FeatureVolume nodes ({}): pick one with --node NAME",
                names()
            ))),
            (Some(n), _) => all
                .iter()
                .copied()
                .find(|f| f.name.as_deref() == Some(n))
                .ok_or_else(|| {
                    missing(format!(
                        "no FeatureVolume named {n:?} (there are: {})",
                        names()
                    ))
                }),
        }
    }

    /// The S-field leaf of `spec` (one of [`VolumeFile::pick`]'s), with noise seed
    /// `seed` (default: the tree's `seed`, 0 for a bare file) and a grid memory budget.
    /// In a tree, `Ground(..)` points resolve on its terrain as when it is compiled.
    pub fn build(
        &self,
        spec: &FeatureVolumeSpec,
        seed: Option<u32>,
        max_memory: u64,
    ) -> Result<SField, SceneError> {
        match self {
            VolumeFile::Bare { path, base_dir, .. } => {
                let opts = BuildOptions {
                    seed: seed.unwrap_or(0),
                    ground: None,
                    max_memory,
                };
                spec.build_with(base_dir, &opts)
                    .map_err(|e| SceneError::Asset {
                        path: path.clone(),
                        node: spec.label(),
                        source: Box::new(e),
                    })
            }
            VolumeFile::Tree(f) => {
                f.build_feature_volume(spec, seed.unwrap_or(f.scene.seed), max_memory)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bare_volumes_are_told_by_their_first_token() {
        assert!(is_bare_volume("FeatureVolume(voxel: 1)"));
        assert!(is_bare_volume(
            "\u{feff}// a cave\n/* note */ FeatureVolume(..)"
        ));
        assert!(!is_bare_volume("(version: 1, root: FeatureVolume(..))"));
        assert!(!is_bare_volume("// FeatureVolume\n(version: 1)"));
    }
}
