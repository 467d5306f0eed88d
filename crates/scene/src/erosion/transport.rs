//! Sediment transport and deposition along the flow graph (Yuan et al. 2019, the `G` term
//! of their erosion–deposition law `∂h/∂t = U − K A^m S^n + (G/A) Q_s`, after Davy and
//! Lague 2009): what running water cuts upstream travels down the drainage, and a share
//! `G·Q_s/A` of the flux settles at every sample it crosses. Where the drainage area grows
//! slowly and the flux is large, below gullies and where valleys open, that share builds
//! fans and valley fill.
//!
//! Explicit, one pass upstream to downstream over the stack backwards (every donor before
//! its receiver): a sample deposits at most what reaches it, and never rises above its
//! highest donor (deposits fill hollows, they do not dam them).

use crate::analysis::flow::FlowGraph;

/// Settles sediment on the samples `z` after one erosion step of the flow graph `graph`
/// (drainage areas `area`, m², of samples of `cell_area` m²): `eroded` is the depth each
/// sample lost in that step, `g` the deposition coefficient `G` (dimensionless, ≥ 0).
/// Returns nothing; `z` rises where sediment settles.
pub fn deposit(
    z: &mut [f32],
    graph: &FlowGraph,
    area: &[f32],
    eroded: &[f32],
    cell_area: f32,
    g: f32,
) {
    let rec = graph.receivers();
    // inflow of each sample (m³), and the highest donor's elevation
    let mut inflow = vec![0.0f32; z.len()];
    let mut top = vec![f32::NEG_INFINITY; z.len()];
    for &k in graph.stack().iter().rev() {
        let k = k as usize;
        let q = inflow[k];
        let mut out = q + eroded[k] * cell_area;
        if q > 0.0 && top[k] > z[k] {
            let settle = (g * q / area[k]).min(q / cell_area).min(top[k] - z[k]);
            z[k] += settle;
            out -= settle * cell_area;
        }
        let r = rec[k] as usize;
        if r != k {
            inflow[r] += out.max(0.0);
            top[r] = top[r].max(z[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A valley's floor steps down from a steep, eroding reach to a flat one: the reach
    /// loses more than settles on it, the flat below gains, no sample rises above its
    /// neighbours, and no more settles than was cut.
    #[test]
    fn sediment_settles_where_the_slope_breaks() {
        let (nx, ny) = (12, 3);
        let mut z: Vec<f32> = (0..nx * ny)
            .map(|k| {
                let i = (k % nx) as f32;
                let j = (k / nx) as f32;
                // steep for x > 6, flat below; a V across the valley
                let floor = if i > 6.0 { 10.0 * (i - 6.0) } else { 0.01 * i };
                floor + 5.0 * (j - 1.0).abs()
            })
            .collect();
        let mut graph = FlowGraph::new();
        graph.update(&z, nx, ny, 1.0, 1.0);
        let mut area = Vec::new();
        graph.accumulate(1.0, &mut area);
        let eroded: Vec<f32> = (0..nx * ny)
            .map(|k| if k % nx > 6 && k / nx == 1 { 0.5 } else { 0.0 })
            .collect();
        let before = z.clone();
        deposit(&mut z, &graph, &area, &eroded, 1.0, 1.0);
        let net = |i: usize| z[i + nx] - before[i + nx] - eroded[i + nx];
        for i in 7..nx - 1 {
            assert!(net(i) < 0.0, "the steep reach gained at {i}: {}", net(i));
        }
        assert!(net(6) > 0.0, "nothing settled below the break");
        for (k, &v) in z.iter().enumerate().take(2 * nx - 1).skip(nx + 1) {
            let top = [k - nx, k + nx, k - 1, k + 1].map(|n| before[n]);
            assert!(v <= top.into_iter().fold(f32::MIN, f32::max) + 1e-6);
        }
        let total: f32 = (0..nx * ny).map(|k| z[k] - before[k]).sum();
        let cut: f32 = eroded.iter().sum();
        assert!(total <= cut + 1e-4, "settled {total} of {cut} cut");
    }
}
