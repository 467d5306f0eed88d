//! Single-flow-direction drainage: each sample sends its water to its steepest-descent
//! neighbour (its *receiver*), and the samples are ordered in a *stack* where every sample
//! comes after its receiver (Braun and Willett 2013, §2.1–2.2: receivers, donors and the
//! stack built by a depth-first walk from the base-level nodes). Traversed forwards, the
//! stack goes downstream to upstream (the implicit stream-power solver's order); backwards,
//! upstream to downstream (the drainage-area accumulation's order). Both are O(n).

use rayon::prelude::*;

use super::NEIGHBOURS;

/// Receivers, distances to them and the stack of an `nx × ny` grid, with buffers reused
/// from one [`FlowGraph::update`] to the next.
#[derive(Clone, Debug, Default)]
pub struct FlowGraph {
    nx: usize,
    ny: usize,
    receiver: Vec<u32>,
    length: Vec<f32>,
    stack: Vec<u32>,
    donor_start: Vec<u32>,
    donors: Vec<u32>,
}

impl FlowGraph {
    /// An empty graph; [`FlowGraph::update`] fills it.
    pub fn new() -> FlowGraph {
        FlowGraph::default()
    }

    /// Whether sample `k` of an `nx × ny` grid `z` is base level: valid and on the grid's
    /// edge or next to nodata (where water leaves the domain, as in
    /// [`super::fill_depressions`]).
    pub fn is_base_level(z: &[f32], nx: usize, ny: usize, k: usize) -> bool {
        Self::base_level(z, nx, ny, k, true)
    }

    /// [`FlowGraph::is_base_level`] told whether the grid has nodata at all (when it has
    /// none, only the edge is base level and the neighbours need no look).
    pub fn base_level(z: &[f32], nx: usize, ny: usize, k: usize, has_nodata: bool) -> bool {
        let (i, j) = (k % nx, k / nx);
        !z[k].is_nan()
            && (i == 0
                || j == 0
                || i + 1 == nx
                || j + 1 == ny
                || has_nodata
                    && NEIGHBOURS.iter().any(|&(di, dj)| {
                        z[(i as isize + di) as usize + nx * (j as isize + dj) as usize].is_nan()
                    }))
    }

    /// Whether any sample of `z` is nodata.
    pub fn has_nodata(z: &[f32]) -> bool {
        z.iter().any(|v| v.is_nan())
    }

    /// Recomputes receivers (steepest descent over the 8 neighbours, slopes measured with
    /// the cell sizes `dx`, `dy`; ties go to the first neighbour in a fixed order) and the
    /// stack for the samples `z` of an `nx × ny` grid. Base-level samples and samples
    /// without a lower neighbour are their own receivers; nodata samples are their own
    /// receivers and stay out of the stack. Returns the number of *pits*: valid samples
    /// that are not base level and have no lower neighbour (none after
    /// [`super::fill_in_place`]).
    ///
    /// # Panics
    ///
    /// If `z.len() != nx · ny` or the grid has more than `u32::MAX` samples (callers check
    /// sizes against the memory budget first).
    pub fn update(&mut self, z: &[f32], nx: usize, ny: usize, dx: f32, dy: f32) -> usize {
        assert_eq!(z.len(), nx * ny, "grid size");
        assert!(
            u32::try_from(z.len()).is_ok(),
            "grid too large for u32 indices"
        );
        self.nx = nx;
        self.ny = ny;
        let n = z.len();
        self.receiver.resize(n, 0);
        self.length.resize(n, 0.0);
        let dist: [f32; 8] = NEIGHBOURS.map(|(di, dj)| (di as f32 * dx).hypot(dj as f32 * dy));
        let offset: [isize; 8] = NEIGHBOURS.map(|(di, dj)| di + nx as isize * dj);
        let has_nodata = Self::has_nodata(z);
        let pits: usize = self
            .receiver
            .par_chunks_mut(nx)
            .zip(self.length.par_chunks_mut(nx))
            .enumerate()
            .map(|(j, (rec, len))| {
                let mut pits = 0;
                for i in 0..nx {
                    let k = i + nx * j;
                    rec[i] = k as u32;
                    len[i] = 1.0;
                    if z[k].is_nan() || Self::base_level(z, nx, ny, k, has_nodata) {
                        continue;
                    }
                    let (mut best, mut steepest) = (k, 0.0f32);
                    for d in 0..8 {
                        let m = (k as isize + offset[d]) as usize;
                        let s = (z[k] - z[m]) / dist[d];
                        if s > steepest {
                            steepest = s;
                            best = m;
                            len[i] = dist[d];
                        }
                    }
                    rec[i] = best as u32;
                    pits += usize::from(best == k);
                }
                pits
            })
            .sum();
        self.build_stack(z);
        pits
    }

    /// Donors (counting sort by receiver) and the depth-first stack from every base node.
    fn build_stack(&mut self, z: &[f32]) {
        let n = z.len();
        self.donor_start.clear();
        self.donor_start.resize(n + 1, 0);
        for (k, &r) in self.receiver.iter().enumerate() {
            if r as usize != k {
                self.donor_start[r as usize + 1] += 1;
            }
        }
        for k in 0..n {
            self.donor_start[k + 1] += self.donor_start[k];
        }
        self.donors.resize(self.donor_start[n] as usize, 0);
        let mut fill = self.donor_start[..n].to_vec();
        for (k, &r) in self.receiver.iter().enumerate() {
            if r as usize != k {
                self.donors[fill[r as usize] as usize] = k as u32;
                fill[r as usize] += 1;
            }
        }
        self.stack.clear();
        let mut todo = Vec::new();
        for (b, v) in z.iter().enumerate() {
            if self.receiver[b] as usize != b || v.is_nan() {
                continue;
            }
            todo.push(b as u32);
            while let Some(c) = todo.pop() {
                self.stack.push(c);
                let c = c as usize;
                let (s, e) = (self.donor_start[c], self.donor_start[c + 1]);
                todo.extend_from_slice(&self.donors[s as usize..e as usize]);
            }
        }
    }

    /// The receiver of every sample (itself for base level, pits and nodata).
    pub fn receivers(&self) -> &[u32] {
        &self.receiver
    }

    /// The distance (metres) from every sample to its receiver (1 where it is its own).
    pub fn lengths(&self) -> &[f32] {
        &self.length
    }

    /// Every valid sample, each after its receiver.
    pub fn stack(&self) -> &[u32] {
        &self.stack
    }

    /// Drainage area (m²) into `area`: each valid sample's `cell_area` plus the areas of
    /// all its donors, accumulated along the stack from upstream to downstream; nodata 0.
    pub fn accumulate(&self, cell_area: f32, area: &mut Vec<f32>) {
        area.clear();
        area.resize(self.receiver.len(), 0.0);
        for &k in &self.stack {
            area[k as usize] = cell_area;
        }
        for &k in self.stack.iter().rev() {
            let r = self.receiver[k as usize] as usize;
            if r != k as usize {
                area[r] += area[k as usize];
            }
        }
    }

    /// Grid width, in samples.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Grid height, in samples.
    pub fn ny(&self) -> usize {
        self.ny
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stack_puts_every_sample_after_its_receiver_and_areas_sum_at_outlets() {
        let (nx, ny) = (23, 17);
        let z: Vec<f32> = (0..nx * ny)
            .map(|k| {
                let (x, y) = ((k % nx) as f32, (k / nx) as f32);
                if (5..7).contains(&(k % nx)) && (8..10).contains(&(k / nx)) {
                    f32::NAN
                } else {
                    30.0 + (x * 0.9).sin() * 4.0 + (y * 0.4).cos() * 5.0 + 0.01 * x * y
                }
            })
            .collect();
        let mut z = z;
        super::super::fill_in_place(&mut z, nx, ny);
        let mut g = FlowGraph::new();
        assert_eq!(g.update(&z, nx, ny, 10.0, 10.0), 0);
        let valid = z.iter().filter(|v| !v.is_nan()).count();
        assert_eq!(g.stack().len(), valid);
        let mut pos = vec![usize::MAX; z.len()];
        for (p, &k) in g.stack().iter().enumerate() {
            pos[k as usize] = p;
        }
        for &k in g.stack() {
            let r = g.receivers()[k as usize] as usize;
            if r != k as usize {
                assert!(pos[r] < pos[k as usize], "{k} before its receiver {r}");
                assert!(z[r] < z[k as usize]);
            } else {
                assert!(FlowGraph::is_base_level(&z, nx, ny, k as usize));
            }
        }
        let mut area = Vec::new();
        g.accumulate(100.0, &mut area);
        let out: f64 = g
            .stack()
            .iter()
            .filter(|&&k| g.receivers()[k as usize] == k)
            .map(|&k| f64::from(area[k as usize]))
            .sum();
        assert!((out - valid as f64 * 100.0).abs() < 1e-3 * out, "{out}");
    }
}
