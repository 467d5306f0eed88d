//! The sizes a generator's parameters may take in its region, checked before it runs: no
//! length longer than the region's diagonal (a gorge's banks wider than the region, a
//! wave band taller than it), no spacing so fine that its samples would pass
//! [`MAX_SAMPLES`], and no count past what one node could ever use. Out of scale, a
//! generator would run for hours on a valid-looking file (`talus: 4294967296`); here it
//! is an error naming the parameter.

use super::LandformError;
use crate::field::Aabb;
use crate::scene::landform::{CaprockSpec, KarstSpec};
use crate::scene::spec::GeneratorSpec;

/// The most samples (Poisson points, lattice nodes) a spacing may ask for.
pub const MAX_SAMPLES: f64 = 16.0 * 1024.0 * 1024.0;

/// The most fallen blocks a metre of cliff face may shed.
const MAX_TALUS: f32 = 1.0;

/// The most symbols of a hoodoo, candidate directions of a karst step.
const MAX_STEPS: u32 = 64;

/// Checks `generator`'s parameters against `region`.
pub fn check(generator: &GeneratorSpec, region: &Aabb) -> Result<(), LandformError> {
    let s = region.size();
    let scale = Scale {
        diagonal: s.length(),
        area: f64::from(s.x) * f64::from(s.y),
        height: f64::from(s.z),
    };
    match generator {
        GeneratorSpec::Karst(k) => karst(&scale, k),
        GeneratorSpec::SeaErosion(g) => {
            let lengths = [
                ("band", g.band.0),
                ("radius", g.radius.0),
                ("reach", g.reach.0),
            ];
            scale.lengths("SeaErosion", &lengths)?;
            scale.spacing("SeaErosion.spacing", g.spacing.0, false)
        }
        GeneratorSpec::Hoodoos(h) => {
            scale.lengths("Hoodoos", &[("size", h.size.0)])?;
            scale.spacing("Hoodoos.spacing", h.spacing.0, false)?;
            count("Hoodoos.max_depth", h.max_depth, MAX_STEPS)
        }
        GeneratorSpec::Canyon(c) => {
            let lengths = [
                ("banks", c.banks.0),
                ("depth", c.depth.0),
                ("radius", c.radius.0),
            ];
            scale.lengths("Canyon", &lengths)?;
            scale.spacing("Canyon.spacing", c.spacing.0, true)
        }
        GeneratorSpec::Arch(a) => {
            let lengths = [
                ("height", a.height),
                ("lintel", a.lintel),
                ("width", a.width),
                ("reach", a.reach),
            ]
            .map(|(n, v)| (n, v.map_or(0.0, |v| v.0)));
            scale.lengths("Arch", &lengths)
        }
        GeneratorSpec::Caprock(c) => caprock(&scale, c),
        GeneratorSpec::SeaCliff(c) => {
            let lengths = [
                ("platform", c.platform.0),
                ("notch", c.notch.0),
                ("reach", c.reach.0),
            ];
            scale.lengths("SeaCliff", &lengths)?;
            scale.spacing("SeaCliff.joints", c.joints.0, false)?;
            talus("SeaCliff", c.talus.0)
        }
    }
}

fn karst(scale: &Scale, k: &KarstSpec) -> Result<(), LandformError> {
    scale.lengths("Karst", &[("radius", k.radius.0)])?;
    scale.spacing("Karst.spacing", k.spacing.0, true)?;
    count("Karst.directions", k.directions, MAX_STEPS)?;
    count("Karst.max_spheres", k.max_spheres, MAX_SAMPLES as u32)
}

fn caprock(scale: &Scale, c: &CaprockSpec) -> Result<(), LandformError> {
    scale.lengths("Caprock", &[("thickness", c.thickness.0)])?;
    scale.spacing("Caprock.joints", c.joints.0, false)?;
    for r in &c.recesses {
        let lengths = [
            ("length", r.length.0),
            ("depth", r.depth.0),
            ("height", r.height.0),
        ];
        scale.lengths("Caprock.recesses", &lengths)?;
    }
    for s in &c.spurs {
        let window = s.window.map_or(0.0, |w| w.0);
        scale.lengths("Caprock.spurs", &[("width", s.width.0), ("window", window)])?;
    }
    talus("Caprock", c.talus.0)
}

/// Fallen blocks a metre of face at most [`MAX_TALUS`].
fn talus(what: &str, v: f32) -> Result<(), LandformError> {
    if v > MAX_TALUS {
        return Err(LandformError::Invalid(format!(
            "`{what}.talus` is {v} blocks a metre of face: at most {MAX_TALUS}"
        )));
    }
    Ok(())
}

/// A region's size.
struct Scale {
    diagonal: f32,
    area: f64,
    height: f64,
}

impl Scale {
    /// Every length of `lengths` (named within `what`) at most the diagonal.
    fn lengths(&self, what: &str, lengths: &[(&str, f32)]) -> Result<(), LandformError> {
        match lengths.iter().find(|(_, v)| !(*v <= self.diagonal)) {
            Some((name, v)) => Err(LandformError::Invalid(format!(
                "`{what}.{name}` is {v} m, longer than the landform region's diagonal ({:.0} m)",
                self.diagonal
            ))),
            None => Ok(()),
        }
    }

    /// A spacing at most the diagonal whose samples over the region (a plane of them, or
    /// with `volume` a lattice through the region's height) stay within [`MAX_SAMPLES`].
    fn spacing(&self, what: &str, v: f32, volume: bool) -> Result<(), LandformError> {
        let (head, field) = what.split_once('.').unwrap_or((what, ""));
        self.lengths(head, &[(field, v)])?;
        let v = f64::from(v);
        let layers = if volume {
            (self.height / v).max(1.0)
        } else {
            1.0
        };
        let samples = self.area / (v * v) * layers;
        if samples > MAX_SAMPLES {
            return Err(LandformError::Invalid(format!(
                "`{what}` of {v} m would take about {samples:.1e} samples over the landform \
                 region: at most {MAX_SAMPLES:.1e}; give a larger spacing or a smaller region"
            )));
        }
        Ok(())
    }
}

/// A count at most `max`.
fn count(what: &str, v: u32, max: u32) -> Result<(), LandformError> {
    if v > max {
        return Err(LandformError::Invalid(format!(
            "`{what}` is {v}: at most {max}"
        )));
    }
    Ok(())
}
