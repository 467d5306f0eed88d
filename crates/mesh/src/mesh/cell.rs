//! What both extractors do per cell and per edge: the asymptotic decider on ambiguous
//! faces and the position of a vertex on a crossed edge.

use super::tables::{Case, FACE_CORNERS};

/// Closest a vertex may come to a grid point, as a fraction of the edge: keeps every
/// triangle's area positive when the field is exactly at the iso-value on a grid point.
pub const EDGE_T_MIN: f32 = 1.0 / 1024.0;

/// Decides the ambiguous faces of `case` with the asymptotic decider (Nielson & Hamann):
/// the solid corners of a face are connected when the bilinear interpolant's saddle lies
/// in the solid. `v` are the corner values minus the iso-value. Bit `n` of the result is
/// set when the `n`-th ambiguous face is connected.
///
/// Only the face's four values enter, in the same order for both cells sharing it, so the
/// two cells decide identically and the mesh stays crack-free.
#[inline]
pub fn ambiguity_mask(case: &Case, v: &[f32; 8]) -> usize {
    let mut mask = 0;
    for n in 0..case.n_ambiguous as usize {
        let [a, b, c, d] = FACE_CORNERS[case.ambiguous[n] as usize].map(|k| v[k as usize]);
        // Saddle value (ad − bc) / (a + d − b − c); the denominator's sign is that of `a`.
        let det = a * d - b * c;
        let connected = if a > 0.0 { det > 0.0 } else { det < 0.0 };
        mask |= (connected as usize) << n;
    }
    mask
}

/// Where the linear interpolant crosses 0 on an edge from `v0` to `v1` (values minus
/// the iso-value, of opposite signs), as a fraction of the edge kept within
/// `[EDGE_T_MIN, 1 − EDGE_T_MIN]`. Non-finite input gives the midpoint.
#[inline]
pub fn edge_t(v0: f32, v1: f32) -> f32 {
    let t = v0 / (v0 - v1);
    if t.is_finite() {
        t.clamp(EDGE_T_MIN, 1.0 - EDGE_T_MIN)
    } else {
        0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::tables::TABLES;

    #[test]
    fn decider_follows_the_saddle() {
        // Face z = 0 of a cell with corners 0 and 3 solid (a diagonal of that face).
        let case = 0b0000_1001;
        let c = TABLES.cases[case];
        assert_eq!(c.n_ambiguous, 1);
        // Strong solid diagonal: saddle solid, connected.
        let strong = [1.0, -0.1, -0.1, 1.0, -1.0, -1.0, -1.0, -1.0];
        assert_eq!(ambiguity_mask(&c, &strong), 1);
        // Weak solid diagonal: saddle empty, separated.
        let weak = [0.1, -1.0, -1.0, 0.1, -1.0, -1.0, -1.0, -1.0];
        assert_eq!(ambiguity_mask(&c, &weak), 0);
        // Two separated corners give two triangles, connected ones a quad band.
        assert_eq!(TABLES.triangles(case, 0).len(), 2);
        assert_eq!(TABLES.triangles(case, 1).len(), 4);
    }

    #[test]
    fn edge_t_interpolates_and_clamps() {
        assert_eq!(edge_t(1.0, -1.0), 0.5);
        assert_eq!(edge_t(0.0, -1.0), EDGE_T_MIN);
        assert_eq!(edge_t(f32::NAN, 1.0), 0.5);
        assert!((edge_t(-0.25, 0.75) - 0.25).abs() < 1e-7);
    }
}
