#!/usr/bin/env python3
"""Side by side, in one run: `karstic erode` against fastscapelib 0.3.0 on the same grid.

Both solve the same landscape evolution model on the same input: uniform uplift of the
interior (the edges are fixed base level), stream-power incision K A^m S^n with
single-flow-direction D8 routing solved implicitly along the stack (Braun and Willett
2013), and linear hillslope diffusion by ADI; fastscapelib resolves depressions with
its MST sink resolver, karstic fills them (Priority-Flood + eps, Barnes et al. 2014).
The input is seeded uniform noise in [0, 1) m written once as an ESRI ASCII grid; both
read the same samples.

Two measurements:

* speed: the median wall time of one time step (uplift, flow routing, accumulation,
  stream power, diffusion) at SIZE x SIZE on one core, in ROUNDS rounds of STEPS steps
  from the input, the two programs alternating; karstic's figure is the median its
  `--timing` flag prints (reading and writing the files are not in it), fastscapelib's
  the median of the same loop timed in Python.
* agreement: both run to steady state at a smaller grid, then the elevation quantiles
  (10 % ... 90 %) of the interior are compared: the largest relative difference.

    pip install fastscapelib==0.3.0 numpy
    cargo build --release --locked
    python3 benches/erosion_vs_fastscapelib.py [--karstic target/release/karstic]
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from machine import machine_line  # noqa: E402

os.environ.setdefault("OMP_NUM_THREADS", "1")
import fastscapelib as fs  # noqa: E402

CELL = 100.0
K, M, N_EXP = 2e-4, 0.4, 1.0
UPLIFT = 1e-3
DIFFUSION = 0.01
DT = 2e4
SEED = 1234


def write_asc(path, z):
    n = z.shape[0]
    with open(path, "w") as f:
        f.write(f"ncols {n}\nnrows {n}\nxllcenter 0\nyllcenter 0\ncellsize {CELL}\n")
        f.write("NODATA_value -99999\n")
        np.savetxt(f, z, fmt="%.6f")


def read_asc(path):
    return np.loadtxt(path, skiprows=6, dtype=np.float64)


def fastscape(z, steps):
    """Runs fastscapelib for `steps` steps; returns (elevation, per-step wall times)."""
    grid = fs.RasterGrid(list(z.shape), [CELL, CELL], fs.NodeStatus.FIXED_VALUE)
    graph = fs.FlowGraph(grid, [fs.SingleFlowRouter(), fs.MSTSinkResolver()])
    spl = fs.SPLEroder(graph, k_coef=K, area_exp=M, slope_exp=N_EXP, tolerance=1e-5)
    diff = fs.DiffusionADIEroder(grid, DIFFUSION)
    uplift = np.full(z.shape, UPLIFT)
    uplift[[0, -1], :] = 0.0
    uplift[:, [0, -1]] = 0.0
    h = z.astype(np.float64).copy()
    times = []
    for _ in range(steps):
        t = time.perf_counter()
        uh = h + DT * uplift
        graph.update_routes(uh)
        area = graph.accumulate(1.0)
        e = spl.erode(uh, area, DT)
        d = diff.erode(uh - e, DT)
        h = uh - e - d
        times.append(time.perf_counter() - t)
    return h, times


def karstic(exe, asc, out, steps):
    """Runs `karstic erode` on one core; returns (elevation, median step time)."""
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    run = subprocess.run(
        [exe, "erode", asc, "-o", out, "--steps", str(steps), "--dt", str(DT),
         "--uplift", str(UPLIFT), "--k", str(K), "--m", str(M), "--n", str(N_EXP),
         "--diffusion", str(DIFFUSION), "--timing", "--quiet"],
        env=env, capture_output=True, text=True,
    )
    if run.returncode != 0:
        sys.exit(f"karstic erode failed:\n{run.stderr}")
    step = float(re.search(r"median step ([0-9.]+) s", run.stdout).group(1))
    return read_asc(out), step


def quantiles(h):
    return np.quantile(h[1:-1, 1:-1], np.linspace(0.1, 0.9, 9))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--karstic", default="target/release/karstic")
    ap.add_argument("--size", type=int, default=1024, help="grid of the speed test")
    ap.add_argument("--steps", type=int, default=8, help="steps of the speed test, a round")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of the speed test")
    ap.add_argument("--steady-size", type=int, default=256)
    ap.add_argument("--steady-steps", type=int, default=500)
    args = ap.parse_args()
    rng = np.random.default_rng(SEED)

    with tempfile.TemporaryDirectory() as tmp:
        asc, out = os.path.join(tmp, "in.asc"), os.path.join(tmp, "out.asc")
        # Speed.
        write_asc(asc, rng.random((args.size, args.size)))
        z = read_asc(asc)
        # The two alternate, round by round, so a change of load on the shared machine
        # falls on both; each round starts from the input.
        fs_times, k_steps = [], []
        for _ in range(args.rounds):
            fs_times += fastscape(z, args.steps)[1]
            k_steps.append(karstic(args.karstic, asc, out, args.steps)[1])
        fs_step, k_step = statistics.median(fs_times), statistics.median(k_steps)
        # Agreement at steady state.
        write_asc(asc, rng.random((args.steady_size, args.steady_size)))
        z = read_asc(asc)
        h_fs, _ = fastscape(z, args.steady_steps)
        h_k, _ = karstic(args.karstic, asc, out, args.steady_steps)

    q_fs, q_k = quantiles(h_fs), quantiles(h_k)
    rel = np.abs(q_k - q_fs) / q_fs
    print(f"{machine_line()}, fastscapelib {fs.__version__}")
    print(f"model: K {K}, m {M}, n {N_EXP}, uplift {UPLIFT} m/yr, diffusion {DIFFUSION} m2/yr, "
          f"dt {DT:.0f} yr, cell {CELL:.0f} m, one core")
    print(f"speed, {args.size}x{args.size}, {args.rounds} alternating rounds of {args.steps} "
          "steps (fastscapelib: median of all steps; karstic: median of the rounds' medians):")
    print(f"  fastscapelib  {fs_step:.3f} s/step")
    print(f"  karstic       {k_step:.3f} s/step")
    print(f"  ratio fastscapelib / karstic: {fs_step / k_step:.2f}x")
    print(f"steady state, {args.steady_size}x{args.steady_size} after {args.steady_steps} steps "
          f"({args.steady_steps * DT / 1e6:.0f} Myr):")
    print("  quantile     " + " ".join(f"{p:7.0f}%" for p in np.linspace(10, 90, 9)))
    print("  fastscapelib " + " ".join(f"{v:8.1f}" for v in q_fs))
    print("  karstic      " + " ".join(f"{v:8.1f}" for v in q_k))
    print(f"  largest relative difference: {100 * rel.max():.2f} %")


if __name__ == "__main__":
    main()
