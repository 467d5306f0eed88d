//! Compiling a scene into the flat [`Tree`] the evaluators run, and the edits of tree
//! files that a compile checks ([`edit`]).

pub mod edit;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use glam::{Affine3A, Quat, Vec3};

use crate::scene::load::to_ron_text;
use crate::scene::spec::{Nary, NodeSpec, Scene};
use crate::scene::{SceneError, SceneFile};
use std::sync::Arc;

use crate::dem::HeightfieldField;
use crate::elevation::{BuildContext, ElevationField, ElevationSpec};
use crate::field::{Aabb, Field, NodeId, Primitive, Transition, Tree, TreeBuilder, Warp};
use crate::field::{Erosion, Rect, Resistance};
use crate::geology::Geology;
use crate::io::DEFAULT_MEMORY_BUDGET;
use crate::io::{content_hash, files_hash};
use crate::landform::Ground;
use crate::scene::{DemCache, HeightfieldSpec};
use crate::voxel::FeatureVolumeSpec;
use crate::voxel::SField;
use crate::voxel::spec::BuildOptions;
use crate::voxel::spec::CurveSource;

/// A compiled scene: the tree, and for each node of the scene's root (pre-order, the order
/// of [`NodeSpec::walk`]) the compiled node it became.
pub struct Compiled {
    /// The tree.
    pub tree: Tree,
    /// `(depth, node)` for each scene node of the root, in pre-order.
    pub outline: Vec<(usize, NodeId)>,
    /// Things the user should know (e.g. a DEM in degrees given metric cells).
    pub notices: Vec<String>,
    /// The scene's terrain: its `terrain` heightfield, or its only one (`None` without).
    pub ground: Option<Arc<HeightfieldField>>,
    /// The scene with its `Landform` nodes expanded into plain primitives, when it had
    /// any: the scene the tree (and [`Compiled::outline`]) was compiled from.
    pub expanded: Option<Scene>,
    /// The scene's geology (uniform [`crate::geology::DEFAULT_RESISTANCE`] without one).
    pub geology: Arc<Geology>,
}

/// Feature Volumes built by this process, by [`volume_key`]: the editor compiles the
/// tree again for each preview of a dragged value, and the volumes, which take most of
/// a compile even when their voxels come from the pipeline's cache (the terrain sampled
/// under them, the cache key, the tricubic bounds), seldom change. An [`SField`] shares
/// its grids: a copy is cheap.
static VOLUMES: Mutex<Vec<(u64, SField)>> = Mutex::new(Vec::new());

/// Volumes kept in [`VOLUMES`].
const VOLUME_MEMO: usize = 8;

/// What a Feature Volume is built from, hashed: its node in the file format's canonical
/// text, the noise seed, the memory budget, the folder of its curve file, the terrain's
/// node and the scene's seed (the `Ground(..)` points and the boundary conditions read
/// the terrain), and the contents of the files these read (a file not there counts as
/// absent). Two builds with the same key give the same volume.
fn volume_key(
    f: &FeatureVolumeSpec,
    seed: u32,
    max_memory: u64,
    base_dir: &Path,
    terrain: Option<TerrainKey>,
) -> u64 {
    let mut files: Vec<PathBuf> = Vec::new();
    if let CurveSource::Path(p) = &f.curves {
        files.push(base_dir.join(p));
    }
    if let Some(source) = terrain.and_then(|(t, ..)| t.source.as_ref()) {
        files.extend(crate::dem::files_read(
            &base_dir.join(source),
            &crate::dem::ReadOptions::default(),
        ));
    }
    let contents = files_hash(&files).to_le_bytes();
    let spec = to_ron_text(f);
    // An amplification without its own region and cell takes the job's (bits: a frame
    // that reads back the same is the same).
    let terrain_text = terrain.map_or(String::new(), |(t, s, frame)| {
        let frame = frame
            .filter(|_| t.amplify.is_some())
            .map(|(r, c)| [r.min.x, r.min.y, r.max.x, r.max.y, c].map(f32::to_bits));
        format!("{} {s} {frame:?}", to_ron_text(t))
    });
    let (seed, max_memory) = (seed.to_le_bytes(), max_memory.to_le_bytes());
    let mut parts: Vec<&[u8]> = vec![
        spec.as_bytes(),
        &seed,
        &max_memory,
        base_dir.as_os_str().as_encoded_bytes(),
        terrain_text.as_bytes(),
    ];
    parts.push(&contents);
    content_hash(&parts)
}

/// What of the terrain a Feature Volume's run depends on: its spec, the scene's seed and
/// the job's frame (an amplification's default region and cell).
type TerrainKey<'a> = (&'a HeightfieldSpec, u32, Option<(Rect, f32)>);

/// The job region's footprint and the job's cell, which a heightfield's `amplify`
/// defaults to.
fn job_frame(scene: &Scene) -> Option<(Rect, f32)> {
    let job = scene.job.as_ref()?;
    let r = job.region.as_ref()?;
    Some((Aabb::new(r.min.0, r.max.0).footprint(), job.cell.get()))
}

/// The node of `scene`'s terrain heightfield (its `terrain`, or its only `Heightfield`),
/// or why it has none.
fn terrain_spec(scene: &Scene) -> Result<&HeightfieldSpec, &'static str> {
    let all = scene.all_nodes();
    let candidates: Vec<&NodeSpec> = match &scene.terrain {
        Some(name) => all
            .into_iter()
            .filter(|n| n.name() == Some(name.as_str()))
            .collect(),
        None => all
            .into_iter()
            .filter(|n| matches!(n, NodeSpec::Heightfield(_)))
            .collect(),
    };
    match candidates.as_slice() {
        [NodeSpec::Heightfield(h)] => Ok(h),
        [] | [_] if scene.terrain.is_some() => {
            Err("the scene's `terrain` must name a Heightfield node")
        }
        [] => Err("terrain anchors need a Heightfield in the scene"),
        _ => Err(
            "the scene has several heightfields: say which one anchors resolve against with `terrain: \"name\"`",
        ),
    }
}

/// Compiles one scene: walks its tree once, children first, into a [`TreeBuilder`].
pub struct Compiler<'s> {
    scene: &'s Scene,
    path: &'s Path,
    base_dir: &'s Path,
    builder: TreeBuilder,
    named: BTreeMap<String, NodeId>,
    outline: Vec<(usize, NodeId)>,
    record: bool,
    dems: DemCache,
    /// The terrain anchors resolve against, loaded on first use.
    terrain: Option<Arc<HeightfieldField>>,
    /// The named nodes, for instances.
    index: HashMap<&'s str, &'s NodeSpec>,
    /// Memory budget of DEMs and voxel grids, bytes.
    budget: u64,
    /// Where the field will be asked for ([`SceneFile::compile_within`]); `None`: anywhere.
    roi: Option<Aabb>,
    /// The scene's geology, built once before the tree.
    geology: Arc<Geology>,
}

impl Compiler<'_> {
    /// The scene's rock resistance (Paris et al. 2019 §4), for the nodes that read it
    /// while they compile: uniform [`crate::geology::DEFAULT_RESISTANCE`] when the scene
    /// has no `geology`.
    pub fn resistance(&self) -> Arc<dyn Resistance> {
        self.geology.clone()
    }

    /// The terrain heightfield (the scene's `terrain`, or its only `Heightfield`).
    fn terrain(&mut self, asking: &NodeSpec) -> Result<Arc<HeightfieldField>, SceneError> {
        if let Some(t) = &self.terrain {
            return Ok(t.clone());
        }
        let spec = terrain_spec(self.scene).map_err(|e| self.error(asking, e))?;
        let hf = spec
            .load_with(
                self.base_dir,
                &mut self.dems,
                self.scene.seed,
                job_frame(self.scene),
            )
            .map_err(|e| self.asset_error(asking, e))?;
        let hf = Arc::new(hf);
        self.terrain = Some(hf.clone());
        Ok(hf)
    }

    /// Runs the voxel pipeline of `f` (node `n`): `Ground(x, y, offset)` points resolve
    /// on the scene's terrain when it has one.
    fn feature_volume(
        &mut self,
        n: &NodeSpec,
        f: &FeatureVolumeSpec,
        seed: u32,
        max_memory: u64,
    ) -> Result<SField, SceneError> {
        let has_terrain = self.scene.terrain.is_some()
            || self
                .scene
                .all_nodes()
                .iter()
                .any(|m| matches!(m, NodeSpec::Heightfield(_)));
        let key = if has_terrain {
            volume_key(
                f,
                seed,
                max_memory,
                self.base_dir,
                Some((
                    terrain_spec(self.scene).map_err(|e| self.error(n, e))?,
                    self.scene.seed,
                    job_frame(self.scene),
                )),
            )
        } else {
            volume_key(f, seed, max_memory, self.base_dir, None)
        };
        let memo = || VOLUMES.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, built)) = memo().iter().find(|(k, _)| *k == key) {
            return Ok(built.clone());
        }
        let terrain = if has_terrain {
            Some(self.terrain(n)?)
        } else {
            None
        };
        let ground = |xy: glam::Vec2| {
            terrain
                .as_ref()
                .map(|t| t.height(xy))
                .filter(|h| h.is_finite())
        };
        let opts = BuildOptions {
            seed,
            ground: Some(&ground),
            max_memory,
        };
        let built = f
            .build_with(self.base_dir, &opts)
            .map_err(|e| self.asset_error(n, e))?;
        let mut memo = memo();
        if memo.len() >= VOLUME_MEMO {
            memo.remove(0);
        }
        memo.push((key, built.clone()));
        Ok(built)
    }

    /// Compiles `n` (a node of the scene, or one derived from it) into a tree of its own,
    /// sharing this compiler's DEM cache.
    fn subtree(&mut self, n: &NodeSpec) -> Result<Tree, SceneError> {
        let mut sub = Compiler::new(self.scene, self.path, self.base_dir, self.budget);
        sub.record = false;
        std::mem::swap(&mut sub.dems, &mut self.dems);
        let id = sub.node(n, 0);
        std::mem::swap(&mut sub.dems, &mut self.dems);
        Ok(sub.builder.build(id?))
    }

    /// Expands every `Landform` node of `n`, innermost first: each base is compiled on
    /// its own, its generator run on it, and the node replaced by the plain result.
    fn expand(&mut self, n: &mut NodeSpec) -> Result<(), SceneError> {
        for c in n.children_mut() {
            self.expand(c)?;
        }
        let NodeSpec::Landform(l) = &*n else {
            return Ok(());
        };
        let tree = self.subtree(&l.base)?;
        let region = l
            .region
            .map_or_else(|| tree.support(), |b| Aabb::new(b.min.0, b.max.0));
        let rock = self.resistance();
        let rho = |p: Vec3| rock.resistance(p);
        let seed = l.full_seed(self.scene.seed);
        let generated = Ground::new(&tree, region, l.cell.0, &rho, seed)
            .and_then(|ground| l.generate(&ground))
            .map_err(|e| self.asset_error(n, e))?;
        if let NodeSpec::Landform(l) = std::mem::replace(n, NodeSpec::Blend(Nary::default())) {
            *n = l.expansion(generated);
        }
        Ok(())
    }

    /// The scene with its landforms expanded (`None` when it has none).
    fn expanded_scene(&mut self) -> Result<Option<Scene>, SceneError> {
        let has = |n: &NodeSpec| {
            let mut found = false;
            n.walk(&mut |m, _| found |= matches!(m, NodeSpec::Landform(_)));
            found
        };
        if !has(&self.scene.root) && !self.scene.defs.iter().any(has) {
            return Ok(None);
        }
        let mut scene = self.scene.clone();
        for d in &mut scene.defs {
            self.expand(d)?;
        }
        self.expand(&mut scene.root)?;
        Ok(Some(scene))
    }

    /// Builds the elevation tree of `e` (node `n`) and implicitizes it.
    fn elevation(&self, n: &NodeSpec, e: &ElevationSpec) -> Result<ElevationField, SceneError> {
        let cx = BuildContext {
            base_dir: self.base_dir,
            seed: self.scene.seed,
            budget: self.budget,
        };
        let tree = e.build_tree(&cx).map_err(|err| self.asset_error(n, err))?;
        ElevationField::new(Arc::new(tree), e.params()).map_err(|err| self.asset_error(n, err))
    }

    /// A replacement's region must be a finite, non-empty box.
    fn check_region(&self, n: &NodeSpec, region: &Aabb) -> Result<(), SceneError> {
        if region.is_empty() || !region.size().is_finite() {
            return Err(self.error(
                n,
                format!(
                    "the region {:?} .. {:?} is empty or unbounded: give `region`",
                    region.min, region.max
                ),
            ));
        }
        Ok(())
    }

    fn error(&self, node: &NodeSpec, message: impl Into<String>) -> SceneError {
        SceneError::Node {
            path: self.path.to_path_buf(),
            node: label(node),
            message: message.into(),
        }
    }

    /// A node whose asset failed, with the asset's error as the source.
    fn asset_error(
        &self,
        node: &NodeSpec,
        e: impl std::error::Error + Send + Sync + 'static,
    ) -> SceneError {
        SceneError::Asset {
            path: self.path.to_path_buf(),
            node: label(node),
            source: Box::new(e),
        }
    }

    fn node(&mut self, n: &NodeSpec, depth: usize) -> Result<NodeId, SceneError> {
        if let Some(&id) = n.name().and_then(|name| self.named.get(name)) {
            // Already compiled for an instance: share it.
            if self.record {
                self.outline.push((depth, id));
            }
            return Ok(id);
        }
        let slot = self.record.then(|| {
            self.outline.push((depth, 0));
            self.outline.len() - 1
        });
        let id = self.node_inner(n, depth)?;
        if let Some(name) = n.name() {
            self.named.insert(name.to_string(), id);
        }
        if let Some(slot) = slot {
            self.outline[slot].1 = id;
        }
        Ok(id)
    }

    fn children(&mut self, cs: &[NodeSpec], depth: usize) -> Result<Vec<NodeId>, SceneError> {
        cs.iter().map(|c| self.node(c, depth + 1)).collect()
    }

    fn node_inner(&mut self, n: &NodeSpec, depth: usize) -> Result<NodeId, SceneError> {
        let name = n.name().map(str::to_string);
        Ok(match n {
            NodeSpec::Primitive(p) => {
                let leaf = Primitive::from_spec(p, self.scene.seed);
                self.builder.primitive(leaf, name)
            }
            NodeSpec::Heightfield(h) => {
                let leaf = h
                    .load_with(
                        self.base_dir,
                        &mut self.dems,
                        self.scene.seed,
                        job_frame(self.scene),
                    )
                    .map_err(|e| self.asset_error(n, e))?;
                self.builder.leaf(Arc::new(leaf), name)
            }
            NodeSpec::Elevation(e) => {
                let leaf = self.elevation(n, e)?;
                self.builder.leaf(Arc::new(leaf), name)
            }
            NodeSpec::FeatureVolume(f) => {
                let leaf = self.feature_volume(n, f, self.scene.seed, self.budget)?;
                self.builder.leaf(Arc::new(leaf), name)
            }
            NodeSpec::Anchor(a) => {
                let terrain = self.terrain(n)?;
                let h = terrain.height(a.at.0);
                if !h.is_finite() {
                    return Err(
                        self.error(n, format!("anchor point {} is outside the terrain", a.at.0))
                    );
                }
                let child = self.node(&a.child, depth + 1)?;
                let m = Affine3A::from_translation(a.at.0.extend(h + a.offset.0));
                self.builder.transform(child, m, name)
            }
            NodeSpec::Blend(x) => {
                let cs = self.children(&x.children, depth)?;
                self.builder.blend(cs, name)
            }
            NodeSpec::Union(x) | NodeSpec::Intersection(x) => {
                if x.children.is_empty() {
                    return Err(self.error(n, "needs at least one child"));
                }
                let cs = self.children(&x.children, depth)?;
                if matches!(n, NodeSpec::Union(_)) {
                    self.builder.union(cs, name)
                } else {
                    self.builder.intersection(cs, name)
                }
            }
            NodeSpec::Difference(d) => {
                let base = self.node(&d.base, depth + 1)?;
                let carves = self.children(&d.carves, depth)?;
                self.builder.difference(base, carves, name)
            }
            NodeSpec::Transform(t) => {
                let rotation = t.rotate.map_or(Quat::IDENTITY, |r| {
                    Quat::from_axis_angle(r.axis.unit(), r.degrees.0.to_radians())
                });
                let m =
                    Affine3A::from_scale_rotation_translation(t.scale.0, rotation, t.translate.0);
                let child = self.node(&t.child, depth + 1)?;
                self.builder.transform(child, m, name)
            }
            NodeSpec::Replace(r) => {
                let base = self.node(&r.base, depth + 1)?;
                // The region, without building the replacement when the file tells it.
                let told = match (&r.region, &*r.by) {
                    (Some(b), _) => Some(Aabb::new(b.min.0, b.max.0)),
                    (None, NodeSpec::FeatureVolume(f)) => {
                        let (_, field) = f.params(self.scene.seed, DEFAULT_MEMORY_BUDGET);
                        Some(field.domain.dilate(-field.falloff))
                    }
                    (None, _) => None,
                };
                if let Some(region) = &told {
                    self.check_region(n, region)?;
                }
                // Outside its region the replacement weighs exactly 0: one that misses
                // the region of interest leaves the base there, unbuilt.
                if let (Some(roi), Some(region)) = (self.roi, told)
                    && !region.overlaps(&roi)
                {
                    return Ok(base);
                }
                let by = self.node(&r.by, depth + 1)?;
                let region = told.unwrap_or_else(|| self.builder.support(by));
                self.check_region(n, &region)?;
                let blend = r
                    .blend
                    .map_or_else(|| 0.125 * region.size().x.min(region.size().y), |b| b.0);
                self.builder
                    .replace(base, by, Transition::new(region, blend), name)
            }
            NodeSpec::Warp(w) => {
                let child = self.node(&w.child, depth + 1)?;
                let region = w.region.map(|r| (Aabb::new(r.min.0, r.max.0), r.falloff.0));
                let warp = Warp::from_spec(&w.turbulence, region, self.scene.seed);
                self.builder.warp(child, warp, name)
            }
            NodeSpec::Erode(e) => {
                let child = self.node(&e.child, depth + 1)?;
                let region = Aabb::new(e.region.min.0, e.region.max.0);
                if region.is_empty() {
                    return Err(self.error(n, "the erosion region is empty: give min <= max"));
                }
                let blend = e
                    .blend
                    .map_or_else(|| 0.125 * region.size().x.min(region.size().y), |b| b.0);
                let erosion = Erosion::new(self.geology.clone(), region, blend, e.strength.0);
                self.builder.erode(child, erosion, name)
            }
            NodeSpec::Landform(l) => {
                // Scenes are expanded before they compile; a landform met here (a subtree
                // compiled on its own) expands in place.
                let mut plain = NodeSpec::Landform(l.clone());
                self.expand(&mut plain)?;
                let record = std::mem::replace(&mut self.record, false);
                let id = self.node(&plain, depth);
                self.record = record;
                id?
            }
            NodeSpec::Instance(i) => {
                if let Some(&id) = self.named.get(&i.of) {
                    return Ok(id);
                }
                let target = *self
                    .index
                    .get(i.of.as_str())
                    .ok_or_else(|| self.error(n, format!("unknown node referenced: {:?}", i.of)))?;
                // Compile the referenced subtree once, outside the outline.
                let record = std::mem::replace(&mut self.record, false);
                let id = self.node(target, depth + 1);
                self.record = record;
                id?
            }
        })
    }
}

impl SceneFile {
    /// Compiles the scene into a tree, within the default memory budget.
    pub fn compile(&self) -> Result<Compiled, SceneError> {
        self.compile_with(DEFAULT_MEMORY_BUDGET)
    }

    /// Compiles the scene into a tree; DEMs and voxel grids are refused beyond `budget`
    /// bytes each, before they are read or allocated.
    pub fn compile_with(&self, budget: u64) -> Result<Compiled, SceneError> {
        let mut first = Compiler::new(&self.scene, &self.path, &self.base_dir, budget);
        let Some(expanded) = first.expanded_scene()? else {
            return first.run();
        };
        let mut plain = Compiler::new(&expanded, &self.path, &self.base_dir, budget);
        plain.dems = first.dems;
        let mut compiled = plain.run()?;
        compiled.expanded = Some(expanded);
        Ok(compiled)
    }

    /// The scene with every `Landform` node expanded into plain primitives, as it
    /// compiles (the scene itself when it has none): what `karstic tree expand` writes.
    pub fn expand(&self) -> Result<Scene, SceneError> {
        Compiler::new(
            &self.scene,
            &self.path,
            &self.base_dir,
            DEFAULT_MEMORY_BUDGET,
        )
        .expanded_scene()
        .map(|e| e.unwrap_or_else(|| self.scene.clone()))
    }

    /// Compiles only what can change the field inside `roi`, for consumers that never ask
    /// outside it (a tile and its halo): a `Replace` whose region misses `roi` becomes its
    /// base, and its replacement — often a Feature Volume, whose voxel pipeline takes
    /// seconds — is not built. Inside `roi` the tree's values equal [`Self::compile_with`]'s
    /// bit for bit (a replacement weighs exactly 0 outside its region); its support and
    /// bounds may be smaller, and the outline lists only the nodes compiled.
    pub fn compile_within(&self, budget: u64, roi: Aabb) -> Result<Compiled, SceneError> {
        let mut c = Compiler::new(&self.scene, &self.path, &self.base_dir, budget);
        c.roi = Some(roi);
        c.run()
    }

    /// The scene's `FeatureVolume` nodes (in `defs` and the tree, pre-order).
    pub fn feature_volumes(&self) -> Vec<&FeatureVolumeSpec> {
        self.scene
            .all_nodes()
            .into_iter()
            .filter_map(|n| match n {
                NodeSpec::FeatureVolume(f) => Some(f),
                _ => None,
            })
            .collect()
    }

    /// The S-field leaf of one of the scene's feature volumes, built as [`Self::compile`]
    /// builds it (the same pipeline cache, `Ground(..)` points on the scene's terrain),
    /// with noise seed `seed` (the scene's is `self.scene.seed`) and a grid memory budget.
    pub fn build_feature_volume(
        &self,
        f: &FeatureVolumeSpec,
        seed: u32,
        max_memory: u64,
    ) -> Result<SField, SceneError> {
        let node = NodeSpec::FeatureVolume(f.clone());
        Compiler::new(&self.scene, &self.path, &self.base_dir, max_memory)
            .feature_volume(&node, f, seed, max_memory)
    }
}

impl<'s> Compiler<'s> {
    fn new(scene: &'s Scene, path: &'s Path, base_dir: &'s Path, budget: u64) -> Self {
        Compiler {
            scene,
            path,
            base_dir,
            builder: TreeBuilder::new(),
            named: BTreeMap::new(),
            outline: Vec::new(),
            record: true,
            dems: DemCache::new(budget),
            terrain: None,
            index: scene.named(),
            budget,
            roi: None,
            geology: Arc::new(scene.geology().unwrap_or_default()),
        }
    }

    fn run(mut self) -> Result<Compiled, SceneError> {
        let root = self.node(&self.scene.root, 0)?;
        let ground = self.terrain(&self.scene.root).ok();
        let tree = self.builder.build(root);
        Ok(Compiled {
            tree,
            ground,
            expanded: None,
            geology: self.geology,
            outline: self.outline,
            notices: self.dems.notices().to_vec(),
        })
    }
}

/// A node in messages: its name, or its kind.
fn label(node: &NodeSpec) -> String {
    node.name()
        .map_or_else(|| node.kind().to_string(), |n| format!("{n:?}"))
}

impl Compiled {
    /// The support of the node named `name` (of `scene`, the scene compiled): the box its
    /// field can change. The outline lists the scene's nodes in pre-order, after its
    /// `Landform` nodes are expanded.
    pub fn support_of(&self, scene: &Scene, name: &str) -> Option<Aabb> {
        let mut hits = Vec::new();
        let walked = self.expanded.as_ref().unwrap_or(scene);
        walked
            .root
            .walk(&mut |n, _| hits.push(n.name() == Some(name)));
        let k = hits.iter().position(|&hit| hit)?;
        let &(_, id) = self.outline.get(k)?;
        Some(self.tree.info(id).support)
    }
}

/// Compiles `scene` within the default memory budget; asset paths are relative to
/// `base_dir`, `path` names the file in errors.
pub fn compile_scene(scene: &Scene, path: &Path, base_dir: &Path) -> Result<Compiled, SceneError> {
    Compiler::new(scene, path, base_dir, DEFAULT_MEMORY_BUDGET).run()
}
