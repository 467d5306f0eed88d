//! Eroded amplification of a DEM: the detail that water and gravity would carve below the
//! DEM's cell, constrained to keep the DEM.
//!
//! Over a rectangle, the DEM is upsampled to a fine lattice, roughened by a little fBm (the
//! seeds of channel heads), then eroded step by step: stream power along the fine
//! drainage where it passes the area of a channel head (Braun and Willett 2013,
//! [`super::stream_power`]; Montgomery and Dietrich 1988), thermal shedding of the
//! slopes above the angle of repose ([`super::thermal`]) and, optionally, transport and
//! deposition ([`super::transport`]). After each step the change `δ` from the upsampled
//! DEM is constrained:
//!
//! * its mean over every DEM cell is brought back to 0, by subtracting the cell means
//!   interpolated bilinearly between the cells' centres (twice; the correction is smooth, so
//!   it adds no seams). The constraint acts as the uplift that balances the incision cell by
//!   cell, so the channels come to the slope–area form of stream power, `S ∝ A^(−m/n)`;
//! * it is softly limited to `relief` metres, `δ ← r·tanh(δ/r)`;
//! * it fades to 0 over a margin around the rectangle (one DEM cell or 16 fine cells, the
//!   larger), so the amplified surface joins the DEM's continuously.
//!
//! The result is an [`Inset`]: the changes `δ` the heightfield leaf adds to its elevation
//! ([`crate::dem::HeightfieldField::with_inset`]) and the traces of the erosion (drainage
//! area, incision, talus, deposits) that the materials and the masks read.

use glam::Vec2;
use rayon::prelude::*;

use super::stream_power::{self, StreamPower};
use super::{thermal, transport};
use crate::analysis::flow::{FlowGraph, mfd_area};
use crate::dem::{DemError, Heightfield, Inset, Interpolation};
use crate::field::Rect;
use crate::field::noise::Fbm;

/// Working memory per fine sample, bytes: the elevations, the upsampled DEM, the taper, the
/// traces, and an [`super::Eroder`]'s flow graph.
pub const BYTES_PER_SAMPLE: u64 = 96;

/// Fine cells of the margin at least (with one DEM cell at least).
const MARGIN_CELLS: f32 = 16.0;

/// Parameters of an amplification (resolved: cell and region known).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifyParams {
    /// The fine lattice's cell, metres.
    pub cell: f32,
    /// The rectangle amplified (tree frame); the margin lies around it.
    pub region: Rect,
    /// Erosion steps.
    pub steps: u32,
    /// Stream-power erodibility per step, `K·dt` (drainage area in m², `n = 1`).
    pub erodibility: f32,
    /// Drainage-area exponent `m` (the channels' concavity `m/n`).
    pub m: f32,
    /// Drainage area where channels start, m² (Montgomery and Dietrich 1988): above it
    /// running water cuts; below it the slope only creeps and sheds.
    pub channel_area: f32,
    /// The most the amplification changes the DEM by, about, metres.
    pub relief: f32,
    /// Hillslope diffusivity per step, m² (rounds the rills and sets the gullies' spacing).
    pub diffusion: f32,
    /// Angle of repose, degrees.
    pub talus: f32,
    /// Amplitude of the initial roughness, metres.
    pub roughness: f32,
    /// Deposition: the transport capacity's coefficient (0: none).
    pub transport: f32,
    /// Noise seed.
    pub seed: u32,
}

/// The fine lattice over `region` grown by the margin, inside the DEM: origin, counts,
/// and the margin's width.
fn lattice(dem: &Heightfield, p: &AmplifyParams) -> Result<(Vec2, usize, usize, f32), DemError> {
    let bad = |what: String| Err(DemError::Invalid { what });
    let c = p.cell;
    if !(c > 0.0 && c.is_finite()) {
        return bad(format!("amplify.cell: a length > 0 metres, got {c}"));
    }
    let margin = dem.cell().max_element().max(MARGIN_CELLS * c);
    let x = dem.extent();
    let lo = (p.region.min - margin).max(x.min);
    let hi = (p.region.max + margin).min(x.max);
    if !(lo.x + 4.0 * c < hi.x && lo.y + 4.0 * c < hi.y) {
        return bad(format!(
            "amplify.region {:?} does not overlap the DEM's extent {x:?}",
            p.region
        ));
    }
    // The lattice steps from the DEM's south-west sample, so it is the same whatever the
    // rectangle's corner.
    let first = ((lo - x.min) / c).ceil() * c + x.min;
    let n = |a: f32, b: f32| ((b - a) / c).floor() as usize + 1;
    Ok((first, n(first.x, hi.x), n(first.y, hi.y), margin))
}

/// Amplifies `dem` (placed, read with `interp`) over `p.region`, within `budget` bytes.
pub fn amplify(
    dem: &Heightfield,
    interp: Interpolation,
    p: &AmplifyParams,
    budget: u64,
) -> Result<Inset, DemError> {
    let (origin, nx, ny, margin) = lattice(dem, p)?;
    let n = nx * ny;
    crate::io::check_budget(
        format!("amplifying a {nx}×{ny} lattice"),
        (n as u64).saturating_mul(BYTES_PER_SAMPLE),
        budget,
    )
    .map_err(|e| DemError::Invalid {
        what: e.to_string(),
    })?;
    let c = p.cell;
    let at = |k: usize| origin + Vec2::new((k % nx) as f32, (k / nx) as f32) * c;
    let mut base = vec![0.0f32; n];
    base.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, v) in row.iter_mut().enumerate() {
            *v = dem.sample(at(i + nx * j), interp);
        }
    });
    // The taper: 1 inside the region, smoothly 0 at the lattice's border.
    let last = at(n - 1);
    let taper: Vec<f32> = (0..n)
        .map(|k| {
            let q = at(k);
            let inner = (q - origin).min(last - q).min_element() / c;
            let outer = (p.region.min - q)
                .max(q - p.region.max)
                .max_element()
                .max(0.0);
            if inner < 1.0 {
                return 0.0;
            }
            let t = (1.0 - outer / margin).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        })
        .collect();
    // From the DEM's cell down: the hollows and spurs a DEM of that cell cannot hold.
    let rough = Fbm::with(p.seed, dem.cell().min_element().max(4.0 * c), 5);
    let mut z: Vec<f32> = (0..n)
        .into_par_iter()
        .map(|k| base[k] + p.roughness * taper[k] * rough.value(at(k).extend(0.0)))
        .collect();
    let mut cons = Constraint::new(dem, origin, nx, ny, c);
    let law = StreamPower {
        k: p.erodibility,
        m: p.m,
        n: 1.0,
    };
    let (mut graph, mut area) = (FlowGraph::new(), Vec::new());
    // The loose cover: talus and alluvium, metres thick, on the rock the water cuts.
    let mut loose = Loose {
        talus: vec![0.0; n],
        alluvium: vec![0.0; n],
    };
    let mut before = vec![0.0f32; n];
    let tan = p.talus.to_radians();
    let mut cut = vec![0.0f32; n];
    let mut channel = vec![0.0f32; n];
    for _ in 0..p.steps {
        stream_power::route(&mut z, nx, ny, c, c, 0.0, &mut graph);
        before.copy_from_slice(&z);
        mfd_area(&z, nx, ny, Vec2::splat(c), 1.0, &mut area);
        // Water cuts where a channel has started; the hillslopes above only creep.
        for (w, &a) in channel.iter_mut().zip(&area) {
            *w = if a >= p.channel_area { a } else { 0.0 };
        }
        stream_power::incise(&mut z, &graph, &channel, law, 1.0);
        for k in 0..n {
            cut[k] = (before[k] - z[k]).max(0.0);
        }
        loose.change(&before, &z, None);
        if p.transport > 0.0 {
            before.copy_from_slice(&z);
            transport::deposit(&mut z, &graph, &area, &cut, c * c, p.transport);
            loose.change(&before, &z, Some(Cover::Alluvium));
        }
        if p.diffusion > 0.0 {
            before.copy_from_slice(&z);
            super::diffusion::step(&mut z, nx, ny, c, c, p.diffusion, 1.0);
            loose.change(&before, &z, None);
        }
        before.copy_from_slice(&z);
        thermal::erode(&mut z, nx, ny, c, c, tan, 0.05, 1);
        loose.change(&before, &z, Some(Cover::Talus));
        cons.apply(&mut z, &base, &taper, p.relief, 2);
    }
    cons.apply(&mut z, &base, &taper, p.relief, 4);
    let delta: Vec<f32> = z
        .iter()
        .zip(&base)
        .map(|(&a, &b)| if (a - b).is_finite() { a - b } else { 0.0 })
        .collect();
    mfd_area(&z, nx, ny, Vec2::splat(c), 1.0, &mut area);
    let incision = delta.iter().map(|d| (-d).max(0.0)).collect();
    // The traces fade with the changes, so nothing shows where the DEM is left as it is.
    for (k, w) in taper.iter().enumerate() {
        area[k] *= w;
        loose.talus[k] *= w;
        loose.alluvium[k] *= w;
    }
    let delta = Heightfield::new(nx, ny, origin, Vec2::splat(c), delta)?;
    Inset::new(delta, [area, incision, loose.talus, loose.alluvium])
}

/// Which loose cover a rise of the ground adds to.
#[derive(Clone, Copy)]
enum Cover {
    Talus,
    Alluvium,
}

/// The loose material on the ground, metres thick per sample: what a process lays down
/// adds to its layer, what any process takes away comes off the alluvium first, then the
/// talus (the youngest deposits lie on top).
struct Loose {
    talus: Vec<f32>,
    alluvium: Vec<f32>,
}

impl Loose {
    /// Follows the ground from `before` to `after`: rises add to `rise`'s layer (none:
    /// ignored), falls strip the layers.
    fn change(&mut self, before: &[f32], after: &[f32], rise: Option<Cover>) {
        for (k, (&b, &a)) in before.iter().zip(after).enumerate() {
            let d = a - b;
            if d > 0.0 {
                match rise {
                    Some(Cover::Talus) => self.talus[k] += d,
                    Some(Cover::Alluvium) => self.alluvium[k] += d,
                    None => {}
                }
            } else if d < 0.0 {
                let off = (-d).min(self.alluvium[k]);
                self.alluvium[k] -= off;
                self.talus[k] = (self.talus[k] + d + off).max(0.0);
            }
        }
    }
}

/// The DEM-cell mean constraint on the fine lattice: which DEM cell each fine sample
/// falls in, and the bilinear weights of the cell centres around it.
struct Constraint {
    /// Per fine sample: its DEM cell (index into the cells `cx × cy` covered).
    cell: Vec<u32>,
    /// Per fine sample: the four cell centres around it and their weights.
    corners: Vec<([u32; 4], [f32; 4])>,
    /// Scratch, reused step to step: the change, and per DEM cell its sum, count and mean.
    d: Vec<f32>,
    sum: Vec<f64>,
    count: Vec<u32>,
    mean: Vec<f32>,
}

impl Constraint {
    fn new(dem: &Heightfield, origin: Vec2, nx: usize, ny: usize, c: f32) -> Constraint {
        let cs = dem.cell();
        let last = origin + Vec2::new((nx - 1) as f32, (ny - 1) as f32) * c;
        let first_cell = ((origin - dem.origin()) / cs).floor();
        let last_cell = ((last - dem.origin()) / cs).floor();
        let (cx, cy) = (
            (last_cell.x - first_cell.x) as usize + 1,
            (last_cell.y - first_cell.y) as usize + 1,
        );
        let idx = |i: usize, j: usize| (i.min(cx - 1) + cx * j.min(cy - 1)) as u32;
        let mut cell = Vec::with_capacity(nx * ny);
        let mut corners = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let q = origin + Vec2::new(i as f32, j as f32) * c;
                let u = (q - dem.origin()) / cs - first_cell;
                cell.push(idx(u.x.max(0.0) as usize, u.y.max(0.0) as usize));
                // between the centres of the cells (at u = a + ½)
                let v = (u - 0.5).max(Vec2::ZERO);
                let (a, b) = (v.x as usize, v.y as usize);
                let (t, s) = ((v.x - a as f32).min(1.0), (v.y - b as f32).min(1.0));
                corners.push((
                    [idx(a, b), idx(a + 1, b), idx(a, b + 1), idx(a + 1, b + 1)],
                    [(1.0 - t) * (1.0 - s), t * (1.0 - s), (1.0 - t) * s, t * s],
                ));
            }
        }
        Constraint {
            cell,
            corners,
            d: Vec::with_capacity(nx * ny),
            sum: vec![0.0; cx * cy],
            count: vec![0; cx * cy],
            mean: vec![0.0; cx * cy],
        }
    }

    /// Constrains `z` against the upsampled DEM `base`: the change softly limited to
    /// `relief`, its cell means taken out `rounds` times, faded by `taper`.
    fn apply(&mut self, z: &mut [f32], base: &[f32], taper: &[f32], relief: f32, rounds: u32) {
        let Constraint {
            cell,
            corners,
            d,
            sum,
            count,
            mean,
        } = self;
        d.clear();
        d.extend(z.iter().zip(base).map(|(&a, &b)| {
            let d = a - b;
            if d.is_finite() {
                relief * (d / relief).tanh()
            } else {
                0.0
            }
        }));
        for _ in 0..rounds {
            sum.fill(0.0);
            count.fill(0);
            for (&c, &v) in cell.iter().zip(d.iter()) {
                sum[c as usize] += f64::from(v);
                count[c as usize] += 1;
            }
            for ((m, &s), &n) in mean.iter_mut().zip(sum.iter()).zip(count.iter()) {
                *m = if n > 0 {
                    (s / f64::from(n)) as f32
                } else {
                    0.0
                };
            }
            let mean = &*mean;
            d.par_iter_mut().zip(&*corners).for_each(|(v, (ids, w))| {
                *v -= (0..4).map(|q| w[q] * mean[ids[q] as usize]).sum::<f32>();
            });
        }
        z.par_iter_mut()
            .zip(base.par_iter().zip(d.par_iter().zip(taper)))
            .for_each(|(z, (&b, (&d, &w)))| {
                if b.is_finite() {
                    *z = b + d * w;
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lattice_starts_on_the_dem_s_steps_and_holds_the_margin() {
        let dem = Heightfield::new(
            40,
            30,
            Vec2::new(100.0, 200.0),
            Vec2::splat(30.0),
            vec![0.0; 1200],
        )
        .unwrap();
        let p = AmplifyParams {
            cell: 2.5,
            region: Rect::new(Vec2::new(400.0, 500.0), Vec2::new(600.0, 650.0)),
            steps: 0,
            erodibility: 0.01,
            m: 0.45,
            channel_area: 2000.0,
            relief: 5.0,
            diffusion: 1.0,
            talus: 35.0,
            roughness: 1.0,
            transport: 0.0,
            seed: 1,
        };
        let (o, nx, ny, margin) = lattice(&dem, &p).unwrap();
        assert_eq!(margin, 40.0);
        assert_eq!(o, Vec2::new(360.0, 460.0));
        assert_eq!((nx, ny), (113, 93));
    }
}
