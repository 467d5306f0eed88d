//! The `Heightfield(...)` node of tree files: a DEM implicitized as in Paris et al. 2019 §5.1.
//!
//! ```ron
//! Heightfield(
//!     name: "jacksboro",
//!     source: "../shared/data/dem/jacksboro_utm16n_90m.tif", // relative to the tree file
//!     falloff: 60.0,            // R, metres
//!     base_depth: 100.0,        // prism floor below the lowest point (default: falloff)
//!     vertical_scale: 1.0,
//!     vertical_offset: 0.0,
//!     placement: (0.0, 0.0),    // where the south-west sample goes
//!     domain: None,             // or [(x, y), ...]: a polygon in the tree frame
//!     interpolation: Bilinear,  // or Bicubic
//!     cell_size: 30.0,          // resample to 30 m cells first
//!     // rock-scale relief (Frasson et al. §5): 3D fBm, rougher on steep and high ground
//!     detail: (noise: (amplitude: 4.0, wavelength: 48.0, octaves: 4), flat: 0.2),
//! )
//! ```
//!
//! Instead of `source`, `generate: (kind: Ridged(wavelength: 2000), ...)` makes the
//! raster from a seed, optionally eroded ([`GenerateSpec`]).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::dem::detail::DetailParams;
use crate::dem::implicit::{HeightfieldField, ImplicitParams};
use crate::dem::{Dem, DemError, Heightfield, Inset, Interpolation, ReadOptions};
use crate::erosion::amplify::{AmplifyParams, amplify};
use crate::field::{Fbm, NoiseSpec, Rect};
use crate::io::DEFAULT_MEMORY_BUDGET;
use crate::procedural::GenerateSpec;
use crate::value::{Finite, NonNegative, P2, Positive, Unit};

fn one() -> Finite {
    Finite(1.0)
}

fn is_one(v: &Finite) -> bool {
    v.0 == 1.0
}

fn is_zero(v: &Finite) -> bool {
    v.0 == 0.0
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

/// `source` is written as a bare path (`source: "dem.tif"`), with or without RON's
/// implicit `Some`.
fn some_path<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<PathBuf>, D::Error> {
    PathBuf::deserialize(d).map(Some)
}

fn path_or_none<S: serde::Serializer>(p: &Option<PathBuf>, s: S) -> Result<S::Ok, S::Error> {
    match p {
        Some(p) => p.serialize(s),
        None => s.serialize_none(),
    }
}

/// A heightfield leaf as written in a tree file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeightfieldSpec {
    /// A name for editors and error messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The DEM file (GeoTIFF, PNG + sidecar, ESRI ASCII, SRTM .hgt), relative to the tree
    /// file's folder. Exactly one of `source` and `generate` is given.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "path_or_none",
        deserialize_with = "some_path"
    )]
    pub source: Option<PathBuf>,
    /// A procedural raster instead of a file: generator, size, seed and erosion stages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GenerateSpec>,
    /// Falloff distance `R` in metres.
    pub falloff: Positive,
    /// Depth of the prism's floor below the lowest elevation (default: `falloff`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_depth: Option<NonNegative>,
    /// Multiplies elevations (default 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub vertical_scale: Finite,
    /// Added to elevations after scaling, metres (default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub vertical_offset: Finite,
    /// Tree-frame position of the DEM's south-west sample (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placement: Option<P2>,
    /// A polygon (tree frame) restricting the domain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<Vec<P2>>,
    /// `Bilinear` (default) or `Bicubic`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub interpolation: Interpolation,
    /// Resample the DEM to cells of this size (metres) before use.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_size: Option<Positive>,
    /// PNG sources without a sidecar: the elevations of raw 0 and of the largest raw value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z_range: Option<(Finite, Finite)>,
    /// Detail amplification (Frasson et al. §5): rock-scale 3D relief on the DEM.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detail: Option<DetailSpec>,
    /// Eroded amplification: gullies, channels, talus and deposits carved below the DEM's
    /// cell over the job's region ([`crate::erosion::amplify`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplify: Option<AmplifySpec>,
}

/// The `amplify:` of a heightfield leaf: `()` for the defaults, over the job's region at
/// the job's cell.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmplifySpec {
    /// The fine lattice's cell, metres (default: the job's cell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell: Option<Positive>,
    /// The rectangle amplified, tree frame, `((x0, y0), (x1, y1))` (default: the job
    /// region's footprint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<(P2, P2)>,
    /// Erosion steps (default 32).
    #[serde(default = "default_amplify_steps")]
    pub steps: u32,
    /// Stream-power erodibility per step, `K·dt`, drainage area in m² (default 0.02).
    #[serde(default = "default_erodibility")]
    pub erodibility: Positive,
    /// Drainage area where channels start, m² (default 2,000): below it the slopes only
    /// creep and shed, so gullies begin partway down and join.
    #[serde(default = "default_channel_area")]
    pub channel_area: NonNegative,
    /// The most the amplification changes the DEM by, about, metres (default 12).
    #[serde(default = "default_relief")]
    pub relief: Positive,
    /// Hillslope diffusivity per step, m² (default 0.5).
    #[serde(default = "default_diffusion")]
    pub diffusion: NonNegative,
    /// Angle of repose of the talus, degrees (default 35).
    #[serde(default = "default_talus")]
    pub talus: Positive,
    /// Amplitude of the initial roughness, metres (default 8).
    #[serde(default = "default_roughness")]
    pub roughness: NonNegative,
    /// Deposition coefficient `G` of the sediment carried down (default 1; 0: none).
    #[serde(default = "default_transport")]
    pub transport: NonNegative,
    /// Added to the scene's seed for the roughness.
    #[serde(default, skip_serializing_if = "is_default")]
    pub seed_offset: u32,
}

/// Most steps an amplification takes.
pub const MAX_AMPLIFY_STEPS: u32 = 1000;

fn default_amplify_steps() -> u32 {
    32
}

fn default_erodibility() -> Positive {
    Positive(0.02)
}

fn default_channel_area() -> NonNegative {
    NonNegative(2000.0)
}

fn default_relief() -> Positive {
    Positive(12.0)
}

fn default_diffusion() -> NonNegative {
    NonNegative(0.5)
}

fn default_talus() -> Positive {
    Positive(35.0)
}

fn default_roughness() -> NonNegative {
    NonNegative(8.0)
}

fn default_transport() -> NonNegative {
    NonNegative(1.0)
}

impl AmplifySpec {
    /// The parameters, the cell and region defaulting to the job's `frame` (its region's
    /// footprint and cell), the noise seeded from the scene's `seed`; an error naming the
    /// field when a value is out of range or nothing gives the region or cell.
    pub fn params(&self, seed: u32, frame: Option<(Rect, f32)>) -> Result<AmplifyParams, String> {
        let region = match (self.region, frame) {
            (Some((a, b)), _) => Rect::new(a.0.min(b.0), a.0.max(b.0)),
            (None, Some((r, _))) => r,
            (None, None) => {
                return Err("amplify.region: give it, or a job region to default to".into());
            }
        };
        let cell = match (self.cell, frame) {
            (Some(c), _) => c.get(),
            (None, Some((_, c))) => c,
            (None, None) => return Err("amplify.cell: give it, or a job to default to".into()),
        };
        if self.steps > MAX_AMPLIFY_STEPS {
            return Err(format!(
                "amplify.steps: at most {MAX_AMPLIFY_STEPS}, got {}",
                self.steps
            ));
        }
        if self.talus.get() >= 90.0 {
            return Err(format!(
                "amplify.talus: a slope angle in degrees below 90, got {}",
                self.talus
            ));
        }
        Ok(AmplifyParams {
            cell,
            region,
            steps: self.steps,
            erodibility: self.erodibility.get(),
            m: AMPLIFY_M,
            channel_area: self.channel_area.get(),
            relief: self.relief.get(),
            diffusion: self.diffusion.get(),
            talus: self.talus.get(),
            roughness: self.roughness.get(),
            transport: self.transport.get(),
            seed: seed.wrapping_add(self.seed_offset),
        })
    }
}

/// The drainage-area exponent of the amplification's stream power: with `n = 1`, the
/// concavity of its channels (Whipple 2004: real rivers 0.35 to 0.65).
pub const AMPLIFY_M: f32 = 0.45;

fn default_flat() -> Unit {
    Unit(0.25)
}

fn default_steep() -> Positive {
    Positive(1.0)
}

fn default_altitude() -> Unit {
    Unit(0.5)
}

/// The `detail:` of a heightfield leaf: `d(p) = A·m(x, y)·t(p)` added to the elevation
/// ([`crate::dem::detail`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetailSpec {
    /// The fBm `t` and its amplitude `A` (metres): wavelength of the first octave,
    /// octaves, seed offset (added to the scene's seed).
    pub noise: NoiseSpec,
    /// Roughness of flat ground relative to steep ground (default 0.25).
    #[serde(default = "default_flat")]
    pub flat: Unit,
    /// Slope (rise over run) from which ground is fully rough (default 1, i.e. 45°).
    #[serde(default = "default_steep")]
    pub steep: Positive,
    /// Weight of altitude in the roughness (default 0.5: the lowest ground is half as
    /// rough as the highest).
    #[serde(default = "default_altitude")]
    pub altitude: Unit,
}

impl DetailSpec {
    /// The detail's parameters, its noise seeded from the scene's `seed`.
    pub fn params(&self, seed: u32) -> DetailParams {
        DetailParams {
            noise: Fbm::new(&self.noise, seed),
            amplitude: self.noise.amplitude.get(),
            flat: self.flat.get(),
            steep: self.steep.get(),
            altitude: self.altitude.get(),
        }
    }
}

impl HeightfieldSpec {
    /// A spec with defaults for everything but the source and falloff.
    pub fn new(source: impl Into<PathBuf>, falloff: f32) -> HeightfieldSpec {
        HeightfieldSpec {
            name: None,
            source: Some(source.into()),
            generate: None,
            falloff: Positive::new(falloff),
            base_depth: None,
            vertical_scale: one(),
            vertical_offset: Finite(0.0),
            placement: None,
            domain: None,
            interpolation: Interpolation::Bilinear,
            cell_size: None,
            z_range: None,
            detail: None,
            amplify: None,
        }
    }

    /// The implicitization parameters this spec asks for, noise seeded from the scene's
    /// `seed`.
    pub fn params(&self, seed: u32) -> ImplicitParams {
        let r = self.falloff.get();
        ImplicitParams {
            falloff: r,
            base_depth: self.base_depth.map_or(r, |b| b.get()),
            vertical_scale: self.vertical_scale.get(),
            vertical_offset: self.vertical_offset.get(),
            placement: self.placement.map_or(glam::Vec2::ZERO, |p| p.0),
            domain: self
                .domain
                .as_ref()
                .map(|d| d.iter().map(|p| p.0).collect()),
            interpolation: self.interpolation,
            detail: self.detail.map(|d| d.params(seed)),
        }
    }

    /// The name, else the source file, for messages.
    fn label(&self) -> String {
        match (&self.name, &self.source) {
            (Some(n), _) => n.clone(),
            (None, Some(s)) => s.to_string_lossy().into_owned(),
            (None, None) => "(generated)".into(),
        }
    }

    /// Loads the DEM (`source` resolved against `base_dir`, or generated) and
    /// implicitizes it (scene seed 0, no job).
    pub fn load(&self, base_dir: &Path) -> Result<HeightfieldField, DemError> {
        self.load_with(base_dir, &mut DemCache::new(DEFAULT_MEMORY_BUDGET), 0, None)
    }

    /// [`HeightfieldSpec::load`] sharing decoded DEMs through `cache` (one per compile),
    /// with the scene's noise `seed` and the job's `frame` (its region's footprint and its
    /// cell), which an `amplify` without its own region and cell takes.
    pub fn load_with(
        &self,
        base_dir: &Path,
        cache: &mut DemCache,
        seed: u32,
        frame: Option<(Rect, f32)>,
    ) -> Result<HeightfieldField, DemError> {
        let named = |e| match e {
            DemError::Invalid { what } => DemError::Invalid {
                what: format!("heightfield {}: {what}", self.label()),
            },
            e => e,
        };
        let dem = match (&self.source, &self.generate) {
            (Some(source), None) => cache.get(&base_dir.join(source), self)?,
            (None, Some(g)) => cache.generated(g, self).map_err(named)?,
            _ => {
                return Err(named(DemError::Invalid {
                    what: "give exactly one of `source` and `generate`".into(),
                }));
            }
        };
        let field = HeightfieldField::new(&dem.heightfield, &self.params(seed))
            .map_err(named)?
            .with_georef(dem.georef.clone());
        let Some(a) = &self.amplify else {
            return Ok(field);
        };
        let p = a
            .params(seed, frame)
            .map_err(|what| named(DemError::Invalid { what }))?;
        let inset = cache.amplified(&dem, &field, &p).map_err(named)?;
        field.with_inset(inset).map_err(named)
    }
}

/// What makes two loads the same: canonical path (or a generator's recipe as RON),
/// resampling (bits), PNG range (bits), interpolation used to resample.
type CacheKey = (PathBuf, Option<u32>, Option<(u32, u32)>, Interpolation);

/// Decoded DEMs by path (and resampling), shared by the heightfield nodes of one compile,
/// with their amplifications, plus the readers' notices for the caller to show.
#[derive(Debug)]
pub struct DemCache {
    budget: u64,
    dems: HashMap<CacheKey, Arc<Dem>>,
    /// Amplifications by DEM (its address in `dems`), placed grid and parameters.
    insets: Vec<(usize, Heightfield, AmplifyParams, Arc<Inset>)>,
    notices: Vec<String>,
}

impl DemCache {
    /// An empty cache whose readers refuse grids over `budget` bytes.
    pub fn new(budget: u64) -> DemCache {
        DemCache {
            budget,
            dems: HashMap::new(),
            insets: Vec::new(),
            notices: Vec::new(),
        }
    }

    /// The amplification `p` of `field` (the leaf built from `dem`), made once per compile.
    fn amplified(
        &mut self,
        dem: &Arc<Dem>,
        field: &HeightfieldField,
        p: &AmplifyParams,
    ) -> Result<Arc<Inset>, DemError> {
        let id = Arc::as_ptr(dem) as usize;
        let placed = field.heightfield();
        if let Some((.., inset)) = self
            .insets
            .iter()
            .find(|(d, hf, q, _)| *d == id && q == p && hf == placed)
        {
            return Ok(inset.clone());
        }
        let interp = field.params().interpolation;
        let inset = Arc::new(amplify(placed, interp, p, self.budget)?);
        self.insets.push((id, placed.clone(), *p, inset.clone()));
        Ok(inset)
    }

    /// Notices of every DEM loaded so far, in load order.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// The raster `g` makes (resampled as `spec` asks), generated once per recipe.
    fn generated(
        &mut self,
        g: &GenerateSpec,
        spec: &HeightfieldSpec,
    ) -> Result<Arc<Dem>, DemError> {
        let recipe = ron::to_string(g).map_err(|e| DemError::Invalid {
            what: format!("generate: {e}"),
        })?;
        let key = (
            PathBuf::from(format!("generate:{recipe}")),
            spec.cell_size.map(|c| c.get().to_bits()),
            None,
            spec.interpolation,
        );
        if let Some(d) = self.dems.get(&key) {
            return Ok(d.clone());
        }
        let hf = g.build(self.budget)?;
        let c = f64::from(hf.cell().x);
        let mut dem = Dem {
            heightfield: hf,
            georef: crate::dem::Georef::local(c, c),
            notices: Vec::new(),
        };
        if let Some(c) = spec.cell_size {
            dem = dem.resample(c.get().into(), spec.interpolation, self.budget)?;
        }
        let dem = Arc::new(dem);
        self.dems.insert(key, dem.clone());
        Ok(dem)
    }

    fn get(&mut self, path: &Path, spec: &HeightfieldSpec) -> Result<Arc<Dem>, DemError> {
        let canon = path.canonicalize().map_err(|source| DemError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let key = (
            canon.clone(),
            spec.cell_size.map(|c| c.get().to_bits()),
            spec.z_range
                .map(|(a, b)| (a.get().to_bits(), b.get().to_bits())),
            spec.interpolation,
        );
        if let Some(d) = self.dems.get(&key) {
            return Ok(d.clone());
        }
        let opts = ReadOptions {
            memory_budget: self.budget,
            z_range: spec
                .z_range
                .map(|(lo, hi)| [lo.get().into(), hi.get().into()]),
            ..ReadOptions::default()
        };
        let mut dem = crate::dem::read(path, &opts)?;
        if let Some(c) = spec.cell_size {
            dem = dem.resample(c.get().into(), spec.interpolation, self.budget)?;
        }
        self.notices.append(&mut dem.notices.clone());
        let dem = Arc::new(dem);
        self.dems.insert(key, dem.clone());
        Ok(dem)
    }
}
