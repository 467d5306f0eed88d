//! Hillslope diffusion `∂h/∂t = D ∇²h` by the alternating-direction implicit scheme
//! (Peaceman and Rachford 1955): a half step implicit along x and explicit along y, then
//! the converse, each a set of tridiagonal systems solved by the Thomas algorithm.
//! Unconditionally stable, so it takes the stream-power solver's time steps.

use crate::analysis::flow::FlowGraph;

/// One diffusion step of `dt` years with diffusivity `d` (m²/yr) on the samples `z` of an
/// `nx × ny` grid of `dx × dy` cells. Base-level samples (the edge, the rim of nodata) and
/// nodata are held fixed.
pub fn step(z: &mut [f32], nx: usize, ny: usize, dx: f32, dy: f32, d: f32, dt: f32) {
    let has_nodata = FlowGraph::has_nodata(z);
    let free: Vec<bool> = (0..z.len())
        .map(|k| !z[k].is_nan() && !FlowGraph::base_level(z, nx, ny, k, has_nodata))
        .collect();
    let rx = f64::from(d) * f64::from(dt) / (2.0 * f64::from(dx) * f64::from(dx));
    let ry = f64::from(d) * f64::from(dt) / (2.0 * f64::from(dy) * f64::from(dy));
    let mut line = Lines::default();
    // x implicit, y explicit.
    let h: Vec<f32> = z.to_vec();
    for j in 0..ny {
        line.solve(
            &free,
            z,
            |i| i + nx * j,
            nx,
            rx,
            |k| explicit(&h, k, nx, ry),
        );
    }
    // y implicit, x explicit.
    let h: Vec<f32> = z.to_vec();
    for i in 0..nx {
        line.solve(&free, z, |j| i + nx * j, ny, ry, |k| explicit(&h, k, 1, rx));
    }
}

/// `h_k + r (h_{k−s} − 2 h_k + h_{k+s})`: the explicit half of a step along stride `s`
/// (only asked of free samples, whose neighbours all exist and are valid).
fn explicit(h: &[f32], k: usize, s: usize, r: f64) -> f64 {
    let c = f64::from(h[k]);
    c + r * (f64::from(h[k - s]) - 2.0 * c + f64::from(h[k + s]))
}

/// Scratch for the Thomas algorithm.
#[derive(Default)]
struct Lines {
    c: Vec<f64>,
    d: Vec<f64>,
}

impl Lines {
    /// Solves `(1 + 2r) h_i − r (h_{i−1} + h_{i+1}) = rhs(i)` on every run of free samples
    /// along a line of `len` samples (`index(i)` its grid index), the fixed samples at both
    /// ends of each run as boundary values; writes the solution into `z`.
    fn solve(
        &mut self,
        free: &[bool],
        z: &mut [f32],
        index: impl Fn(usize) -> usize,
        len: usize,
        r: f64,
        rhs: impl Fn(usize) -> f64,
    ) {
        let mut i = 0;
        while i < len {
            if !free[index(i)] {
                i += 1;
                continue;
            }
            let s = i;
            while i < len && free[index(i)] {
                i += 1;
            }
            // Run [s, i): free samples never touch the edge, so s − 1 and i are fixed.
            let (lo, hi) = (f64::from(z[index(s - 1)]), f64::from(z[index(i)]));
            self.c.clear();
            self.d.clear();
            let b = 1.0 + 2.0 * r;
            for t in s..i {
                let mut d = rhs(index(t));
                if t == s {
                    d += r * lo;
                }
                if t + 1 == i {
                    d += r * hi;
                }
                let (cp, dp) = match (self.c.last(), self.d.last()) {
                    (Some(&cp), Some(&dp)) => (cp, dp),
                    _ => (0.0, 0.0),
                };
                let m = b + r * cp;
                self.c.push(-r / m);
                self.d.push((d + r * dp) / m);
            }
            let mut next = 0.0;
            for t in (s..i).rev() {
                let o = t - s;
                let v = self.d[o] - self.c[o] * next;
                z[index(t)] = v as f32;
                next = v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diffusion_smooths_a_bump_keeps_the_edge_and_matches_the_heat_kernel_decay() {
        // A sine mode sin(πx/L) sin(πy/L) decays as exp(−2π²D t / L²) under diffusion.
        let (nx, dx) = (41usize, 10.0f32);
        let l = (nx - 1) as f32 * dx;
        let mode = |k: usize| {
            let (x, y) = ((k % nx) as f32 * dx, (k / nx) as f32 * dx);
            (std::f32::consts::PI * x / l).sin() * (std::f32::consts::PI * y / l).sin()
        };
        let mut z: Vec<f32> = (0..nx * nx).map(|k| 100.0 * mode(k)).collect();
        let (d, dt, steps) = (1.0f32, 200.0f32, 50);
        for _ in 0..steps {
            step(&mut z, nx, nx, dx, dx, d, dt);
        }
        let t = dt * steps as f32;
        let want = 100.0 * (-2.0 * std::f32::consts::PI.powi(2) * d * t / (l * l)).exp();
        let centre = z[nx / 2 + nx * (nx / 2)];
        assert!((centre - want).abs() < 0.02 * want, "{centre} vs {want}");
        assert!(want < 60.0, "the test should decay visibly: {want}");
        for (i, v) in z.iter().take(nx).enumerate() {
            assert!(v.abs() < 1e-3, "edge sample {i} moved: {v}");
        }
    }
}
