//! Cross-section profiles of curve and contour primitives (Génevaux et al. 2015 §4.1): a
//! piecewise-linear function of a distance, constant beyond its first and last keys. The
//! paper stores piecewise quadrics; linear pieces keep the Lipschitz bound exact (the
//! steepest piece) and are what a user types.

use serde::{Deserialize, Serialize};

use crate::field::Interval;
use crate::value::Finite;

/// A profile `c(d)`: keys `(d, dz)` in increasing `d`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Vec<(Finite, Finite)>", into = "Vec<(Finite, Finite)>")]
pub struct Profile {
    keys: Vec<(f32, f32)>,
    lipschitz: f32,
    range: Interval,
}

impl TryFrom<Vec<(Finite, Finite)>> for Profile {
    type Error = String;
    fn try_from(v: Vec<(Finite, Finite)>) -> Result<Self, String> {
        Profile::new(v.into_iter().map(|(d, z)| (d.0, z.0)).collect())
    }
}

impl From<Profile> for Vec<(Finite, Finite)> {
    fn from(p: Profile) -> Self {
        p.keys
            .into_iter()
            .map(|(d, z)| (Finite(d), Finite(z)))
            .collect()
    }
}

impl Profile {
    /// A profile through `keys` (`(distance, elevation offset)`, finite, at least one, in
    /// strictly increasing distance).
    pub fn new(keys: Vec<(f32, f32)>) -> Result<Profile, String> {
        if keys.is_empty() {
            return Err("a profile needs at least one key (distance, elevation)".into());
        }
        if keys.iter().any(|(d, z)| !d.is_finite() || !z.is_finite()) {
            return Err("profile keys must be finite".into());
        }
        if let Some(w) = keys.windows(2).find(|w| w[1].0 <= w[0].0) {
            return Err(format!(
                "profile keys must be in strictly increasing distance, found {} after {}",
                w[1].0, w[0].0
            ));
        }
        let lipschitz = keys
            .windows(2)
            .map(|w| ((w[1].1 - w[0].1) / (w[1].0 - w[0].0)).abs())
            .fold(0.0, f32::max)
            * 1.000_1;
        let range = keys
            .iter()
            .fold(Interval::EMPTY, |r, &(_, z)| r.hull(Interval::point(z)));
        Ok(Profile {
            keys,
            lipschitz,
            range,
        })
    }

    /// `c(d)`.
    #[inline]
    pub fn value(&self, d: f32) -> f32 {
        let k = &self.keys;
        if d <= k[0].0 {
            return k[0].1;
        }
        for w in k.windows(2) {
            if d <= w[1].0 {
                let t = (d - w[0].0) / (w[1].0 - w[0].0);
                return w[0].1 + (w[1].1 - w[0].1) * t;
            }
        }
        k[k.len() - 1].1
    }

    /// `max |c'|`.
    pub fn lipschitz(&self) -> f32 {
        self.lipschitz
    }

    /// The range of `c`.
    pub fn range(&self) -> Interval {
        self.range
    }

    /// True when the profile rises away from its skeleton (a valley: the last key above
    /// the first), false for a ridge or a crest.
    pub fn is_valley(&self) -> bool {
        self.keys[self.keys.len() - 1].1 >= self.keys[0].1
    }
}
