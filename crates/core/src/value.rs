//! The value types of the file format: validated numbers, points, boxes and regions, and
//! the RON options every file of the format is read with.
//!
//! These check themselves while the file is parsed, so RON reports a bad value with the
//! line and column where it stands ("expected a finite number", "radius must be > 0").
//! Spec types of every node use them instead of bare `f32`.

use std::fmt;

use glam::{Vec2, Vec3};
use ron::extensions::Extensions;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

fn finite<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    let v = f64::deserialize(d)?;
    if !v.is_finite() || v.abs() > f32::MAX as f64 {
        return Err(D::Error::custom(format!(
            "expected a finite number, found {v}"
        )));
    }
    Ok(v as f32)
}

macro_rules! checked_scalar {
    ($(#[$doc:meta])* $name:ident, $ok:expr, $what:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Default)]
        pub struct $name(pub f32);

        impl $name {
            /// The value, after a check that panics only on programmer error.
            pub fn new(v: f32) -> Self {
                assert!(v.is_finite() && $ok(v), concat!("expected ", $what));
                $name(v)
            }

            /// The number.
            pub fn get(self) -> f32 {
                self.0
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = finite(d)?;
                if !$ok(v) {
                    return Err(D::Error::custom(format!(concat!("expected ", $what, ", found {}"), v)));
                }
                Ok($name(v))
            }
        }

        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_f32(self.0)
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.0.fmt(f)
            }
        }
    };
}

checked_scalar!(
    /// Any finite number.
    Finite,
    |_v: f32| true,
    "a finite number"
);
checked_scalar!(
    /// A finite number `> 0` (radii, falloffs, sizes, wavelengths).
    Positive,
    |v: f32| v > 0.0,
    "a number > 0"
);
checked_scalar!(
    /// A finite number `≥ 0` (amplitudes, depths).
    NonNegative,
    |v: f32| v >= 0.0,
    "a number >= 0"
);
checked_scalar!(
    /// A number in `[0, 1]` (weights, fractions).
    Unit,
    |v: f32| (0.0..=1.0).contains(&v),
    "a number in [0, 1]"
);

/// A point or vector `(x, y, z)` with finite coordinates, in metres.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct P3(pub Vec3);

impl<'de> Deserialize<'de> for P3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y, z] = <[Finite; 3]>::deserialize(d)?;
        Ok(P3(Vec3::new(x.0, y.0, z.0)))
    }
}

impl Serialize for P3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (self.0.x, self.0.y, self.0.z).serialize(s)
    }
}

/// A 2D point `(x, y)` with finite coordinates, in metres.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct P2(pub Vec2);

impl<'de> Deserialize<'de> for P2 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y] = <[Finite; 2]>::deserialize(d)?;
        Ok(P2(Vec2::new(x.0, y.0)))
    }
}

impl Serialize for P2 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (self.0.x, self.0.y).serialize(s)
    }
}

/// Per-axis factors `(x, y, z)`, none of them 0 (negative mirrors).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale3(pub Vec3);

impl<'de> Deserialize<'de> for Scale3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let P3(v) = P3::deserialize(d)?;
        if v.abs().min_element() < 1e-6 {
            return Err(D::Error::custom(format!(
                "expected non-zero scale factors, found {v}"
            )));
        }
        Ok(Scale3(v))
    }
}

impl Serialize for Scale3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        P3(self.0).serialize(s)
    }
}

impl Default for Scale3 {
    fn default() -> Self {
        Scale3(Vec3::ONE)
    }
}

/// A non-zero direction `(x, y, z)`; normalised when used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dir3(pub Vec3);

impl<'de> Deserialize<'de> for Dir3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let P3(v) = P3::deserialize(d)?;
        if v.length_squared() < 1e-12 {
            return Err(D::Error::custom("expected a non-zero direction"));
        }
        Ok(Dir3(v))
    }
}

impl Serialize for Dir3 {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        P3(self.0).serialize(s)
    }
}

impl Dir3 {
    /// The unit vector.
    pub fn unit(self) -> Vec3 {
        self.0.normalize()
    }
}

/// A box region with a falloff around it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, try_from = "RawRegion")]
pub struct Region {
    /// Lower corner.
    pub min: P3,
    /// Upper corner.
    pub max: P3,
    /// Width of the falloff around the box, in metres.
    pub falloff: Positive,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    min: P3,
    max: P3,
    falloff: Positive,
}

impl TryFrom<RawRegion> for Region {
    type Error = String;
    fn try_from(r: RawRegion) -> Result<Self, String> {
        if r.min.0.cmpgt(r.max.0).any() {
            return Err(format!(
                "region min {:?} must be <= max {:?} on every axis",
                r.min.0, r.max.0
            ));
        }
        Ok(Region {
            min: r.min,
            max: r.max,
            falloff: r.falloff,
        })
    }
}

/// An axis-aligned box `(min: (x, y, z), max: (x, y, z))`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Lower corner.
    pub min: P3,
    /// Upper corner.
    pub max: P3,
}

/// How deep the brackets of a file of the format may nest: about 160 nodes inside one
/// another (a node takes about six levels), and within what the parser's recursion takes
/// on a thread's stack.
pub const MAX_NESTING: usize = 1024;

/// The RON options of tree files: `Some` may be left out, a node's fields may be written
/// straight inside its kind, `Blend(children: [...])`, and brackets nest at most
/// [`MAX_NESTING`] deep.
pub fn ron_options() -> ron::Options {
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES)
        .with_recursion_limit(MAX_NESTING)
}

/// A RON parse error of `text`, a file that should hold `what` (e.g. "a tree"), in words
/// for the user: as RON says it, but
/// * a file nested past [`MAX_NESTING`] is said so (RON's own words name its API);
/// * an error at the file's first token says the file is not `what`, quoting nothing of
///   it: a path that names some other file (a key, a password file) must not have its
///   first word echoed.
pub fn ron_message(e: &ron::error::SpannedError, text: &str, what: &str) -> String {
    if e.code == ron::Error::ExceededRecursionLimit {
        return format!(
            "brackets nest deeper than {MAX_NESTING} levels here: karstic reads files nested \
             up to that depth (about 160 nodes inside one another)"
        );
    }
    let first = first_token(text);
    if (e.span.start.line, e.span.start.col) <= first {
        return format!("this is not {what}: it should start with `(`");
    }
    e.code.to_string()
}

/// Line and column (from 1) of the first character of `text` that is neither blank nor
/// in a comment, nor the `#![enable(..)]` header (where RON's first error can stand).
fn first_token(text: &str) -> (usize, usize) {
    let (mut line, mut col) = (1, 1);
    let mut rest = text;
    loop {
        let trimmed = rest.trim_start();
        for c in rest[..rest.len() - trimmed.len()].chars() {
            (line, col) = if c == '\n' {
                (line + 1, 1)
            } else {
                (line, col + 1)
            };
        }
        rest = trimmed;
        let skip = if rest.starts_with("//") {
            rest.find('\n').unwrap_or(rest.len())
        } else if rest.starts_with("/*") {
            rest.find("*/").map_or(rest.len(), |i| i + 2)
        } else {
            return (line, col);
        };
        for c in rest[..skip].chars() {
            (line, col) = if c == '\n' {
                (line + 1, 1)
            } else {
                (line, col + 1)
            };
        }
        rest = &rest[skip..];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_at_the_first_token_quotes_nothing_of_the_file() {
        let text = "// a comment\n  root:$6$secret:19000:0:99999:7:::\n";
        let e = ron::from_str::<P3>(text).unwrap_err();
        let m = ron_message(&e, text, "a tree");
        assert!(!m.contains("root") && m.contains("not a tree"), "{m}");
        let text = "(1, 2, x)";
        let e = ron::from_str::<P3>(text).unwrap_err();
        assert!(!ron_message(&e, text, "a point").contains("not a point"));
    }

    #[test]
    fn rejects_bad_numbers_with_position() {
        let e = ron::from_str::<Positive>("\n  -2.0").unwrap_err();
        assert_eq!(e.span.start.line, 2);
        assert!(e.to_string().contains("expected a number > 0"), "{e}");
        assert!(ron::from_str::<Finite>("NaN").is_err());
        assert!(ron::from_str::<Finite>("inf").is_err());
        assert!(ron::from_str::<Dir3>("(0, 0, 0)").is_err());
        assert_eq!(
            ron::from_str::<P3>("(1, 2.5, -3)").unwrap().0,
            Vec3::new(1.0, 2.5, -3.0)
        );
    }
}
