//! The tree-file form of skeletons, validated while parsing so errors carry positions.

use glam::{Vec2, Vec3};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::polygon::validate_polygon;
use crate::value::{Dir3, Finite, P2, P3, Positive};

/// A skeleton as written in a tree file (RON), e.g. `Sphere(center: (0, 0, 10), radius: 4)`.
///
/// ```text
/// Point(center: (x, y, z))
/// Segment(a: (..), b: (..))                     // a = b is a point
/// Polyline(points: [(..), (..), ...])           // ≥ 2 points
/// Curve(points: [(..), (..), ...])              // ≥ 2 control points, centripetal Catmull-Rom through them
/// Disc(center: (..), normal: (..), radius: r)
/// Plane(point: (..), normal: (..), half_size: h) // the square patch |u|, |v| ≤ h of the plane
/// Sphere(center: (..), radius: r)
/// Box(center: (..), half_size: (hx, hy, hz), yaw: 30)   // yaw in degrees about +z, default 0
/// Ellipsoid(center: (..), radii: (rx, ry, rz))
/// Cone(base: (..), apex: (..), radius: r)       // solid, capped by its base disc
/// Capsule(a: (..), b: (..), radius: r)
/// Prism(polygon: [(x, y), ...], z: (lo, hi))    // simple polygon, ≥ 3 vertices, lo < hi
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum SkeletonSpec {
    /// A point.
    Point {
        /// The point.
        center: P3,
    },
    /// A segment.
    Segment {
        /// First end.
        a: P3,
        /// Second end.
        b: P3,
    },
    /// A polyline.
    Polyline {
        /// Its vertices, at least 2.
        points: Points,
    },
    /// A smooth curve through control points.
    Curve {
        /// Control points the curve passes through, at least 2.
        points: Points,
    },
    /// A filled disc.
    Disc {
        /// Centre.
        center: P3,
        /// Normal (normalised).
        normal: Dir3,
        /// Radius.
        radius: Positive,
    },
    /// A filled square patch of a plane.
    Plane {
        /// Centre of the patch.
        point: P3,
        /// Normal of the plane (normalised).
        normal: Dir3,
        /// Half the side of the square.
        half_size: Positive,
    },
    /// A solid ball.
    Sphere {
        /// Centre.
        center: P3,
        /// Radius.
        radius: Positive,
    },
    /// A solid box.
    Box {
        /// Centre.
        center: P3,
        /// Half extents along its own axes.
        half_size: Size3,
        /// Turn about +z in degrees (counter-clockwise seen from above).
        #[serde(default)]
        yaw: Finite,
    },
    /// A solid axis-aligned ellipsoid.
    Ellipsoid {
        /// Centre.
        center: P3,
        /// Semi-axes along x, y, z.
        radii: Size3,
    },
    /// A solid cone capped by its base disc.
    Cone {
        /// Centre of the base disc.
        base: P3,
        /// Apex (must differ from `base`).
        apex: P3,
        /// Radius of the base.
        radius: Positive,
    },
    /// A solid capsule (a segment grown by `radius`).
    Capsule {
        /// First end of the axis.
        a: P3,
        /// Second end of the axis.
        b: P3,
        /// Radius.
        radius: Positive,
    },
    /// A solid vertical prism.
    Prism {
        /// Simple polygon of the XY plane, in any orientation.
        polygon: Polygon,
        /// z range `(lo, hi)`.
        z: ZRange,
    },
}

impl SkeletonSpec {
    /// The checks serde cannot make field by field: a cone's apex must not lie on its
    /// base. (Everything else is validated while parsing.)
    pub fn check(&self) -> Result<(), String> {
        if let SkeletonSpec::Cone { base, apex, radius } = self
            && super::Cone::new(base.0, apex.0, radius.get()).is_none()
        {
            return Err(format!(
                "a cone's apex must differ from its base, both are at {}",
                base.0
            ));
        }
        Ok(())
    }
}

/// At least 2 points `[(x, y, z), ...]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Points(pub Vec<P3>);

impl<'de> Deserialize<'de> for Points {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<P3>::deserialize(d)?;
        if v.len() < 2 {
            return Err(D::Error::custom(format!(
                "expected at least 2 points, found {}",
                v.len()
            )));
        }
        Ok(Points(v))
    }
}

impl Serialize for Points {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

/// Three positive sizes `(x, y, z)` in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Size3(pub Vec3);

impl<'de> Deserialize<'de> for Size3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y, z] = <[Positive; 3]>::deserialize(d)?;
        Ok(Size3(Vec3::new(x.0, y.0, z.0)))
    }
}

impl Serialize for Size3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        P3(self.0).serialize(s)
    }
}

/// A z range `(lo, hi)` with `lo < hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZRange(f32, f32);

impl ZRange {
    /// `(lo, hi)`, or `None` unless `lo < hi` (both finite).
    pub fn new(lo: f32, hi: f32) -> Option<Self> {
        (lo.is_finite() && hi.is_finite() && lo < hi).then_some(ZRange(lo, hi))
    }

    /// Bottom.
    pub fn lo(&self) -> f32 {
        self.0
    }

    /// Top.
    pub fn hi(&self) -> f32 {
        self.1
    }
}

impl<'de> Deserialize<'de> for ZRange {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let (lo, hi) = <(Finite, Finite)>::deserialize(d)?;
        ZRange::new(lo.0, hi.0).ok_or_else(|| {
            D::Error::custom(format!(
                "expected a z range (lo, hi) with lo < hi, found ({}, {})",
                lo.0, hi.0
            ))
        })
    }
}

impl Serialize for ZRange {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (self.0, self.1).serialize(s)
    }
}

/// A simple polygon `[(x, y), ...]`: at least 3 distinct vertices, no self-intersection,
/// non-zero area. Keeps the vertices as written (for a lossless round trip).
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon(Vec<P2>);

impl Polygon {
    /// The polygon, or the reason it is not simple.
    pub fn new(points: Vec<P2>) -> Result<Self, String> {
        let v: Vec<Vec2> = points.iter().map(|p| p.0).collect();
        validate_polygon(&v)?;
        Ok(Polygon(points))
    }

    /// The vertices as written.
    pub fn points(&self) -> &[P2] {
        &self.0
    }

    /// The cleaned vertices, counter-clockwise.
    pub fn vertices(&self) -> Vec<Vec2> {
        let v: Vec<Vec2> = self.0.iter().map(|p| p.0).collect();
        validate_polygon(&v).expect("validated at construction")
    }
}

impl<'de> Deserialize<'de> for Polygon {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Polygon::new(Vec::<P2>::deserialize(d)?).map_err(D::Error::custom)
    }
}

impl Serialize for Polygon {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}
