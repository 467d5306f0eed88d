//! S-field leaves ([`SField`]: Feature Curves through the voxel pipeline) on the tape: the
//! `SFIELD` op, whose sparse bricks travel in two storage buffers read by
//! `crates/render/shaders/sfield.wgsl`.
//!
//! * `sf_table` (`u32`): per level, its brick table (`u32::MAX` for a missing brick), x
//!   fastest.
//! * `sf_data` (`f32`): per level, S (and α, β when the field has displacement noise) in
//!   the pipeline's own brick order (512 nodes a brick); with the tricubic blend, the
//!   finest level's blend weights.
//!
//! | params | meaning |
//! | --- | --- |
//! | `min.xyz, max.xyz` | the domain box |
//! | `R, R_f, ±1, noisy, levels, L_S', tricubic, weights` | sigmoid width, face falloff, orientation (`−1` solid, `+1` air), displacement noise (0/1), level count, the global Lipschitz bound of `S'`, tricubic blend (0/1), offset of its weights |
//! | `fbm` | the displacement noise ([`super::noise::encode_fbm`]) |
//! | per level ([`sf_level`]) | `origin.xyz, h, dims.xyz`, offsets of its table, S, α, β |
//!
//! The offsets of all of them are named in [`sfield`].
//!
//! **Value**: [`SField`]'s own, `min(σ(∓S'), 2T(1 − g(d_in/R_f)))` in the domain and 0
//! outside, with `S'` sampled as [`SField::s_value`] samples it: on the finest level whose
//! cell around the point (clamped to the domain) is complete, trilinear, blended with the
//! tricubic stencil on the finest level, minus the displacement `α·fbm(β·(p − min))`.
//!
//! **Bound** over the ball `B(c, r)` ([`bound`]): `S'` read through the clamp to the domain
//! is `L_S'`-Lipschitz everywhere, so over the ball it lies in `S'(c) ± L_S'·r`; the bound
//! is `max(max σ' over that range · L_S', the face falloff's slope over the ball's range
//! of d_in)` — [`SField`]'s `lipschitz_box` with its per-brick ranges replaced by that
//! interval: one more sample instead of a walk over up to 4,096 bricks per level, which
//! the GPU could not afford (see lavapipe's loop budget in `docs/rendering.md`). Far from
//! the surface σ' vanishes over the range and steps are long; near it the bound is the
//! global one. The CPU twin evaluates the [`SField`] itself with this bound, so both
//! tracers step alike. Offsets travel as f32, exact below 2²⁴: larger grids are refused
//! with [`TapeError::Limits`].

use glam::Vec3;

use super::TapeError;
use super::format::{fbm, limit, set3, sf_level, sfield};
use super::noise::encode_fbm;
use crate::curves::Orientation;
use crate::field::falloff::{ISO, sigma_slope, wyvill_slope};
use crate::field::{Aabb, Interval};
use crate::voxel::SField;
use crate::voxel::sparse::BRICK_NODES;

/// `−1` for a solid, `+1` for an air orientation: the field is `σ(sign·S')`.
fn sign(sf: &SField) -> f32 {
    match sf.params().orientation {
        Orientation::Solid => -1.0,
        Orientation::Air => 1.0,
    }
}

/// Appends the grids of the non-empty `sf` to `table` and `data` and returns its
/// parameters. `what` names the leaf in errors.
pub fn encode(
    sf: &SField,
    table: &mut Vec<u32>,
    data: &mut Vec<f32>,
    what: &str,
) -> Result<Vec<f32>, TapeError> {
    let p = sf.params();
    let vol = sf.volume();
    let noisy = sf.noise_amplitude() > 0.0;
    let offset = |n: usize| -> Result<f32, TapeError> {
        if n > limit::MAX_OFFSET {
            return Err(TapeError::Limits(format!(
                "{what}: its bricks need {n} table entries or samples; the GPU encoding addresses at most {}",
                limit::MAX_OFFSET
            )));
        }
        Ok(n as f32)
    };
    let mut q = vec![0.0; sfield::HEAD + sf_level::LEN * vol.levels.len()];
    for (l, bricks) in vol.levels.iter().enumerate() {
        let g = bricks.geom;
        let bd = g.bdims();
        let table_at = offset(table.len())?;
        for z in 0..bd.z {
            for y in 0..bd.y {
                for x in 0..bd.x {
                    table.push(bricks.brick(glam::IVec3::new(x, y, z)));
                }
            }
        }
        let nodes = bricks.len() * BRICK_NODES;
        let mut channel = |c: &[f32]| -> Result<f32, TapeError> {
            let at = offset(data.len())?;
            data.extend_from_slice(&c[..nodes]);
            Ok(at)
        };
        let s_at = channel(&vol.s[l])?;
        let (a_at, b_at) = if noisy {
            (channel(&vol.alpha[l])?, channel(&vol.beta[l])?)
        } else {
            (0.0, 0.0)
        };
        let lv = &mut q[sfield::HEAD + l * sf_level::LEN..][..sf_level::LEN];
        set3(lv, sf_level::ORIGIN, g.origin);
        lv[sf_level::H] = g.h;
        set3(lv, sf_level::DIMS, g.dims.as_vec3());
        lv[sf_level::TABLE] = table_at;
        lv[sf_level::S] = s_at;
        lv[sf_level::ALPHA] = a_at;
        lv[sf_level::BETA] = b_at;
    }
    let weights_at = match sf.cubic() {
        Some(c) => {
            let at = offset(data.len())?;
            data.extend_from_slice(c.weights());
            at
        }
        None => 0.0,
    };
    offset(table.len().max(data.len()))?;
    let d = p.domain;
    set3(&mut q, sfield::MIN, d.min);
    set3(&mut q, sfield::MAX, d.max);
    q[sfield::TRANSITION] = p.transition;
    q[sfield::FALLOFF] = p.falloff;
    q[sfield::SIGN] = sign(sf);
    q[sfield::NOISY] = if noisy { 1.0 } else { 0.0 };
    q[sfield::LEVELS] = vol.levels.len() as f32;
    q[sfield::S_LIPSCHITZ] = sf.s_lipschitz();
    q[sfield::TRICUBIC] = if sf.cubic().is_some() { 1.0 } else { 0.0 };
    q[sfield::WEIGHTS] = weights_at;
    q[sfield::FBM..sfield::FBM + fbm::LEN].copy_from_slice(&encode_fbm(0, &p.fbm));
    Ok(q)
}

/// A Lipschitz bound of the S-field leaf over the ball `B(c, r)` (see the module's
/// documentation): the CPU twin of `sf_bound` in `crates/render/shaders/sfield.wgsl`, given
/// `s_c = S'(c)` ([`SField::s_value`]).
pub fn bound(sf: &SField, s_c: f32, c: Vec3, r: f32) -> f32 {
    let p = sf.params();
    let d = p.domain;
    let ball = Aabb::around(c, r);
    if !ball.overlaps(&d) {
        return 0.0;
    }
    let bc = ball.intersection(d);
    let ls = sf.s_lipschitz();
    let x = sign(sf) * s_c;
    let sig = sigma_slope(Interval::new(x - ls * r, x + ls * r), p.transition) * ls;
    let lo = (bc.min - d.min).min(d.max - bc.max).min_element().max(0.0);
    let hi = (bc.max - d.min).min(d.max - bc.min).min_element().max(0.0);
    let f = p.falloff;
    let face = 2.0 * ISO * wyvill_slope(Interval::new(lo / f, hi / f)) / f;
    sig.max(face)
}

/// `(f(p), bound over B(c, r))` of the S-field leaf: the field's own value and [`bound`].
pub fn eval(sf: &SField, (p, c, r): (Vec3, Vec3, f32), with_bound: bool) -> (f32, f32) {
    use crate::field::Field;
    let v = sf.value(p);
    if !with_bound {
        return (v, 0.0);
    }
    (v, bound(sf, sf.s_value(c), c, r))
}
