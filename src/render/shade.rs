//! Terrain shading: sun diffuse with shadow rays, a hemisphere sky ambient, distance fog,
//! and a material tint by slope and altitude (Frasson et al. §5: rock on steep faces, grass on
//! low flats, snow on high flats).
//!
//! Colours are linear RGB in `[0, 1]`; [`to_srgb8`] encodes them for the PNG. The GPU
//! shader (`shaders/trace.wgsl`) mirrors these formulas; keep the two in step.

use glam::Vec3;

use crate::field::Aabb;

/// Lighting, fog and material parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Unit vector towards the sun.
    pub sun: Vec3,
    /// Sun radiance.
    pub sun_color: Vec3,
    /// Ambient light from the zenith.
    pub sky_color: Vec3,
    /// Ambient light from below the horizon (bounce off the ground).
    pub ground_color: Vec3,
    /// Colour of the air far away.
    pub fog_color: Vec3,
    /// Distance (metres) over which fog covers `1 − 1/e` of the colour; `∞` disables it.
    pub fog_distance: f32,
    /// Trace shadow rays towards the sun.
    pub shadows: bool,
    /// Albedo of steep faces.
    pub rock: Vec3,
    /// Albedo of low flats.
    pub grass: Vec3,
    /// Albedo of high flats.
    pub snow: Vec3,
    /// Normal `z` below which the surface is rock, and above which it is fully flat
    /// material (smooth blend between the two).
    pub rock_slope: (f32, f32),
    /// Altitude (metres) where flats turn from grass to snow.
    pub snow_line: f32,
    /// Width (metres) of the grass–snow transition.
    pub snow_blend: f32,
}

impl Shading {
    /// Defaults for a scene in `support`: sun from the south-west at 40° elevation, fog
    /// distance six times the box diagonal, snow on the top quarter of the box's height.
    pub fn for_scene(support: &Aabb) -> Self {
        let height = support.size().z.max(1e-3);
        Shading {
            sun: Vec3::new(-0.55, -0.45, 0.7).normalize(),
            sun_color: Vec3::new(1.0, 0.92, 0.8) * 2.4,
            sky_color: Vec3::new(0.2, 0.26, 0.38),
            ground_color: Vec3::new(0.07, 0.06, 0.05),
            fog_color: Vec3::new(0.6, 0.68, 0.8),
            fog_distance: 12.0 * support.radius().max(1e-3),
            shadows: true,
            rock: Vec3::new(0.2, 0.17, 0.14),
            grass: Vec3::new(0.09, 0.2, 0.045),
            snow: Vec3::new(0.8, 0.82, 0.86),
            rock_slope: (0.6, 0.8),
            snow_line: support.min.z + 0.75 * height,
            snow_blend: 0.05 * height,
        }
    }

    /// Sky colour seen along a unit direction (a horizon-to-zenith gradient).
    pub fn sky(&self, dir: Vec3) -> Vec3 {
        let k = dir.z.clamp(0.0, 1.0).sqrt();
        self.fog_color.lerp(self.sky_color * 0.9, k)
    }

    /// Albedo at height `z` with outward normal `n`.
    pub fn albedo(&self, z: f32, n: Vec3) -> Vec3 {
        let flat = smoothstep(self.rock_slope.0, self.rock_slope.1, n.z);
        let snowy = smoothstep(
            self.snow_line - self.snow_blend,
            self.snow_line + self.snow_blend,
            z,
        );
        let top = self.grass.lerp(self.snow, snowy);
        self.rock.lerp(top, flat)
    }

    /// Colour of a surface point `p` with outward normal `n`, hit at distance `t` along a
    /// ray; `lit` is 1 when the sun reaches it and 0 in shadow.
    pub fn surface(&self, p: Vec3, n: Vec3, t: f32, lit: f32) -> Vec3 {
        let albedo = self.albedo(p.z, n);
        let diffuse = n.dot(self.sun).max(0.0) * lit;
        let ambient = self.ground_color.lerp(self.sky_color, 0.5 + 0.5 * n.z);
        let c = albedo * (self.sun_color * diffuse + ambient);
        self.fog(c, t)
    }

    /// Blends `c` seen at distance `t` towards the fog colour.
    pub fn fog(&self, c: Vec3, t: f32) -> Vec3 {
        let k = 1.0 - (-t / self.fog_distance).exp();
        c.lerp(self.fog_color, k)
    }
}

/// Hermite step from 0 at `a` to 1 at `b`.
#[inline]
pub fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let u = ((x - a) / (b - a)).clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// Entries of the gamma table: linear values are quantised to 1/4095 before encoding.
const GAMMA_STEPS: usize = 4096;

/// Linear `[0, 1]` RGB to 8-bit sRGB (gamma 2.2), opaque, through a table (a `powf` per
/// channel was a visible share of a frame's time).
pub fn to_srgb8(c: Vec3) -> [u8; 4] {
    static TABLE: std::sync::OnceLock<[u8; GAMMA_STEPS]> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            ((i as f32 / (GAMMA_STEPS - 1) as f32).powf(1.0 / 2.2) * 255.0 + 0.5) as u8
        })
    });
    let e = |v: f32| table[(v.clamp(0.0, 1.0) * (GAMMA_STEPS - 1) as f32 + 0.5) as usize];
    [e(c.x), e(c.y), e(c.z), 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Shading {
        Shading::for_scene(&Aabb::new(Vec3::ZERO, Vec3::new(100.0, 100.0, 40.0)))
    }

    #[test]
    fn tint_follows_slope_and_altitude() {
        let s = scene();
        assert_eq!(s.albedo(5.0, Vec3::Z), s.grass, "low flat is grass");
        assert_eq!(s.albedo(39.0, Vec3::Z), s.snow, "high flat is snow");
        assert_eq!(
            s.albedo(39.0, Vec3::X),
            s.rock,
            "steep is rock at any height"
        );
        assert_eq!(s.albedo(5.0, Vec3::new(1.0, 0.0, 0.3).normalize()), s.rock);
    }

    #[test]
    fn shadow_and_fog_darken_and_veil() {
        let s = scene();
        let p = Vec3::new(0.0, 0.0, 5.0);
        let lit = s.surface(p, Vec3::Z, 0.0, 1.0);
        let dark = s.surface(p, Vec3::Z, 0.0, 0.0);
        assert!(lit.length() > dark.length() * 1.5);
        let far = s.surface(p, Vec3::Z, 1e9, 1.0);
        assert!((far - s.fog_color).length() < 1e-4);
        assert_eq!(to_srgb8(Vec3::ONE), [255, 255, 255, 255]);
        assert_eq!(to_srgb8(Vec3::ZERO), [0, 0, 0, 255]);
    }
}
