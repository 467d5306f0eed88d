//! Loading the Feature Curve scenes of `trees/curves/` through the scene loader, as users'
//! tree files are: the compiled tree, the `FeatureVolume` spec of its root, its resolved
//! primitives and its S-field leaf (the same pipeline run, from the build cache).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use karstic::curves::Features;

use karstic::field::Tree;
use karstic::voxel::FeatureVolumeSpec;
use karstic::voxel::SField;

/// `trees/curves/`.
pub fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves")
}

/// A compiled scene of `trees/curves/NAME.ron`.
pub struct Loaded {
    /// The tree file's seed.
    pub seed: u32,
    /// The compiled tree (`scene::load(path)?.compile()?`).
    pub tree: Tree,
    /// The volume's spec.
    pub spec: FeatureVolumeSpec,
    /// Its primitives, resolved.
    pub features: Features,
    /// Its S-field leaf.
    pub leaf: SField,
}

/// Loads and compiles `trees/curves/NAME.ron`.
pub fn load(name: &str) -> Loaded {
    let file = karstic::scene::load(dir().join(format!("{name}.ron"))).unwrap();
    let tree = file.compile().unwrap().tree;
    let spec = file.feature_volumes()[0].clone();
    let features = spec
        .feature_set(&file.base_dir)
        .unwrap()
        .resolve(&|_| None)
        .unwrap();
    let leaf = file
        .build_feature_volume(&spec, file.scene.seed, 1 << 32)
        .unwrap();
    Loaded {
        seed: file.scene.seed,
        tree,
        spec,
        features,
        leaf,
    }
}
