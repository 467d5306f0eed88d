//! A pinhole look-at camera (Z up) and its rays.

use glam::Vec3;

use super::RenderError;
use crate::field::Aabb;

/// Largest accepted image side, in pixels.
pub const MAX_SIDE: u32 = 32_768;

/// The vertical field of view (degrees) of a picture whose tree file and command give
/// none.
pub const DEFAULT_FOV: f32 = 40.0;

/// A ray `o + t·d` with a unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

impl Ray {
    /// The point at parameter `t` (metres along the ray).
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// The parameter range `[t0, t1]` (with `t0 ≥ 0`) inside the box `b` (slab test), or
    /// `None` when the ray misses it.
    pub fn clip(&self, b: &Aabb) -> Option<(f32, f32)> {
        let inv = self.dir.recip();
        let a = (b.min - self.origin) * inv;
        let c = (b.max - self.origin) * inv;
        // 0·∞ = NaN for rays parallel to a slab through its plane: min/max ignore NaN.
        let t0 = a.min(c).max_element().max(0.0);
        let t1 = a.max(c).min_element();
        (t0 <= t1).then_some((t0, t1))
    }
}

/// A pinhole camera looking from `eye` at `target` with a vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    half_h: f32,
}

impl Camera {
    /// A camera at `eye` looking at `target` (Z up), `fov_y` degrees vertically, for a
    /// `width × height` image. Errors on degenerate input (coincident points, a view
    /// straight up or down, a field of view outside `(0, 179]`, a bad size).
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        check_size(width, height)?;
        if !(eye.is_finite() && target.is_finite()) {
            return Err(RenderError::BadCamera(
                "eye and target must be finite".into(),
            ));
        }
        check_fov(fov_y)?;
        let towards = target - eye;
        if !towards.is_finite() {
            return Err(RenderError::BadCamera(format!(
                "eye {eye} and target {target} are too far apart to aim from one at the other"
            )));
        }
        // Scaled first: the square of a length past about 1e19 m overflows f32.
        let forward =
            (towards / towards.abs().max_element().max(f32::MIN_POSITIVE)).normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err(RenderError::BadCamera("eye and target coincide".into()));
        }
        let right = forward.cross(Vec3::Z);
        if right.length() < 1e-4 {
            return Err(RenderError::BadCamera(
                "the view direction is vertical; tilt it so that Z can be up in the image".into(),
            ));
        }
        let right = right.normalize();
        Ok(Camera {
            eye,
            target,
            fov_y,
            width,
            height,
            forward,
            right,
            up: right.cross(forward),
            half_h: (0.5 * fov_y.to_radians()).tan(),
        })
    }

    /// The camera a tree file's `job` or a command line asks for: looking from `eye` at
    /// `target` when `look` gives them, otherwise framing `frame` ([`Camera::frame`]).
    /// `karstic render --camera` and `karstic run` both build theirs here.
    pub fn view(
        look: Option<(Vec3, Vec3)>,
        frame: &Aabb,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        match look {
            Some((eye, target)) => Camera::look_at(eye, target, fov_y, width, height),
            None => Camera::frame(frame, fov_y, width, height),
        }
    }

    /// The default framing of a field's support box: a three-quarter view from the
    /// south-east (+X, −Y) and above, from the closest point that keeps all eight corners
    /// in view (the view is shifted sideways and vertically so that the box is centred in
    /// the image, not the box's centre).
    pub fn frame(support: &Aabb, fov_y: f32, width: u32, height: u32) -> Result<Self, RenderError> {
        if support.is_empty() {
            return Err(RenderError::EmptySupport(
                "the field is zero everywhere".into(),
            ));
        }
        if !(support.min.is_finite() && support.max.is_finite()) {
            return Err(RenderError::EmptySupport(format!(
                "{} .. {}",
                support.min, support.max
            )));
        }
        let centre = support.center();
        let dir = Vec3::new(1.0, -1.0, 0.9).normalize();
        // Orientation only: the basis does not depend on the eye's position.
        let probe = Camera::look_at(centre + dir, centre, fov_y, width, height)?;
        let (right, up, forward, tan_v) = probe.basis();
        let tan_h = tan_v * width as f32 / height as f32;
        // With the eye at centre + dir·D + right·a + up·b, corner c (relative to the centre)
        // is in view when |c·up − b| ≤ tan_v (c·forward + D), and likewise sideways. The
        // smallest D admitting some b is half the spread of c·up ∓ tan_v c·forward over
        // tan_v; b is then the middle of what remains.
        let corners = support.corners().map(|c| c - centre);
        let fit = |axis: Vec3, tan: f32| {
            let lo = corners
                .iter()
                .map(|c| c.dot(axis) - tan * c.dot(forward))
                .fold(f32::MIN, f32::max);
            let hi = corners
                .iter()
                .map(|c| c.dot(axis) + tan * c.dot(forward))
                .fold(f32::MAX, f32::min);
            ((lo - hi) / (2.0 * tan), lo, hi)
        };
        let (dv, lo_v, hi_v) = fit(up, tan_v);
        let (dh, lo_h, hi_h) = fit(right, tan_h);
        let dist = dv.max(dh).max(1e-3) * 1.05;
        let b = 0.5 * (lo_v + hi_v);
        let a = 0.5 * (lo_h + hi_h);
        let shift = right * a + up * b;
        Camera::look_at(
            centre + dir * dist + shift,
            centre + shift,
            fov_y,
            width,
            height,
        )
    }

    /// The ray through the image point `(x, y)` in pixels (`(0, 0)` the top-left corner,
    /// pixel centres at half-integers).
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let aspect = self.width as f32 / self.height as f32;
        let u = (2.0 * x / self.width as f32 - 1.0) * self.half_h * aspect;
        let v = (1.0 - 2.0 * y / self.height as f32) * self.half_h;
        Ray {
            origin: self.eye,
            dir: (self.forward + self.right * u + self.up * v).normalize(),
        }
    }

    /// The ray through the centre of pixel `(i, j)`.
    #[inline]
    pub fn pixel_ray(&self, i: u32, j: u32) -> Ray {
        self.ray(i as f32 + 0.5, j as f32 + 0.5)
    }

    /// Angular size of a pixel (radians, at the image centre): the footprint of a pixel at
    /// distance `t` is about `t` times this.
    pub fn pixel_angle(&self) -> f32 {
        2.0 * self.half_h / self.height as f32
    }

    /// The camera basis `(right, up, forward)` and `tan(fov_y / 2)`, for the GPU uniforms.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3, f32) {
        (self.right, self.up, self.forward, self.half_h)
    }
}

/// Errors on a vertical field of view outside `(0°, 179°]`.
pub fn check_fov(fov_y: f32) -> Result<(), RenderError> {
    if !(fov_y > 0.0 && fov_y <= 179.0) {
        return Err(RenderError::BadCamera(format!(
            "field of view {fov_y}° is outside (0°, 179°]"
        )));
    }
    Ok(())
}

/// Errors on an image side of 0 or above [`MAX_SIDE`].
pub fn check_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(RenderError::BadSize { width, height });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_points_at_target_and_corners_span_the_fov() {
        let cam = Camera::look_at(Vec3::new(10.0, -10.0, 5.0), Vec3::ZERO, 60.0, 200, 100).unwrap();
        let c = cam.ray(100.0, 50.0);
        assert!((c.dir - (-cam.eye).normalize()).length() < 1e-5);
        let top = cam.ray(100.0, 0.0);
        let bottom = cam.ray(100.0, 100.0);
        let angle = top.dir.angle_between(bottom.dir).to_degrees();
        assert!((angle - 60.0).abs() < 1e-3, "{angle}");
        assert!(top.dir.z > bottom.dir.z, "image y runs downwards");
        let left = cam.ray(0.0, 50.0);
        let right = cam.ray(200.0, 50.0);
        assert!(
            left.dir.cross(right.dir).z < 0.0,
            "image x runs to the right"
        );
    }

    #[test]
    fn framing_sees_every_corner_of_the_box() {
        let b = Aabb::new(Vec3::new(-50.0, -20.0, 0.0), Vec3::new(150.0, 80.0, 30.0));
        let cam = Camera::frame(&b, 45.0, 320, 180).unwrap();
        assert!(cam.eye.x > b.max.x && cam.eye.y < b.min.y && cam.eye.z > b.max.z);
        let (r, u, f, half) = cam.basis();
        for c in b.corners() {
            let d = c - cam.eye;
            let z = d.dot(f);
            assert!(z > 0.0);
            assert!((d.dot(u) / z).abs() <= half);
            assert!((d.dot(r) / z).abs() <= half * 320.0 / 180.0);
        }
    }

    #[test]
    fn clipping_matches_the_box() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let r = Ray {
            origin: Vec3::new(-5.0, 0.0, 0.0),
            dir: Vec3::X,
        };
        assert_eq!(r.clip(&b), Some((4.0, 6.0)));
        let inside = Ray {
            origin: Vec3::ZERO,
            dir: Vec3::Z,
        };
        assert_eq!(inside.clip(&b), Some((0.0, 1.0)));
        let miss = Ray {
            origin: Vec3::new(-5.0, 2.0, 0.0),
            dir: Vec3::X,
        };
        assert_eq!(miss.clip(&b), None);
        let behind = Ray {
            origin: Vec3::new(5.0, 0.0, 0.0),
            dir: Vec3::X,
        };
        assert_eq!(behind.clip(&b), None);
    }

    #[test]
    fn degenerate_cameras_are_errors() {
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, 45.0, 10, 10).is_err());
        assert!(Camera::look_at(Vec3::Z, Vec3::ZERO, 45.0, 10, 10).is_err());
        assert!(Camera::look_at(Vec3::X, Vec3::ZERO, 0.0, 10, 10).is_err());
        assert!(Camera::look_at(Vec3::X, Vec3::ZERO, 45.0, 0, 10).is_err());
        assert!(Camera::frame(&Aabb::EMPTY, 45.0, 10, 10).is_err());
    }

    #[test]
    fn view_looks_where_asked_or_frames_the_box() {
        let b = Aabb::new(Vec3::new(-50.0, -20.0, 0.0), Vec3::new(150.0, 80.0, 30.0));
        let look = (Vec3::new(0.0, -300.0, 100.0), Vec3::new(10.0, 0.0, 0.0));
        let asked = Camera::view(Some(look), &b, 30.0, 64, 48).unwrap();
        assert_eq!((asked.eye, asked.target), look);
        let framed = Camera::view(None, &b, 30.0, 64, 48).unwrap();
        assert_eq!(framed, Camera::frame(&b, 30.0, 64, 48).unwrap());
        assert!(Camera::view(Some((Vec3::ONE, Vec3::ONE)), &b, 30.0, 64, 48).is_err());
    }
}
