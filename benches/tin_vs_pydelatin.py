#!/usr/bin/env python3
"""Side by side, in one run: `karstic tin` against pydelatin on the same heightfield.

The input is the issue's anchor case: a 1025 × 1025 heightfield of 1000 m relief,
triangulated to a 5 m maximum vertical error. It is a spectral fBm (seeded, power-law
amplitude k^-beta) written once as an ESRI ASCII grid; pydelatin gets the very samples
karstic reads from that file. Both run on one core: pydelatin is single-threaded, and
karstic's greedy insertion is sequential (RAYON_NUM_THREADS=1 all the same). The figure
compared is the triangulation alone: `Delatin(...)` for pydelatin, the "triangulation"
time `karstic tin` prints for karstic (reading the file and writing the glTF are
reported apart, as the command's total).

    pip install pydelatin numpy
    cargo build --release --locked
    python3 benches/tin_vs_pydelatin.py [--karstic target/release/karstic] [--runs 7]
        [--anchor OTHER_KARSTIC]

With `--anchor`, a second karstic binary (e.g. one built from an earlier commit) runs in
the same rotation, so a before/after ratio comes from the very runs pydelatin's does.
Pin the whole script to one core (`taskset -c 0 python3 ...`) to keep karstic and
pydelatin on the same core.
"""

import argparse
import filecmp
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from machine import machine_line  # noqa: E402
from pydelatin import Delatin

N = 1025
RELIEF = 1000.0
MAX_ERROR = 5.0
# Roughness chosen so that the triangle count is near the anchor's (245k at 5 m).
BETA = 1.78
SEED = 7


def heightfield():
    """The seeded spectral fBm, scaled to [0, RELIEF] metres, rows north first."""
    rng = np.random.default_rng(SEED)
    kx = np.fft.fftfreq(N)[:, None]
    ky = np.fft.fftfreq(N)[None, :]
    k = np.sqrt(kx**2 + ky**2)
    k[0, 0] = 1.0
    amp = k**-BETA
    amp[0, 0] = 0.0
    z = np.real(np.fft.ifft2(amp * np.exp(2j * np.pi * rng.random((N, N)))))
    return (z - z.min()) / (z.max() - z.min()) * RELIEF


def write_asc(path, z):
    with open(path, "w") as f:
        f.write(f"ncols {N}\nnrows {N}\nxllcenter 0\nyllcenter 0\ncellsize 10\n")
        f.write("NODATA_value -99999\n")
        np.savetxt(f, z, fmt="%.3f")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--karstic", default="target/release/karstic")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--anchor", help="another karstic binary, run in the same rotation")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        asc = os.path.join(tmp, "fbm1025.asc")
        write_asc(asc, heightfield())
        # The samples exactly as written (three decimals), float32 as karstic reads them.
        z = np.loadtxt(asc, skiprows=6, dtype=np.float32)

        env = dict(os.environ, RAYON_NUM_THREADS="1")
        delatin, delatin_cpu = [], []
        binaries = [("karstic", args.karstic)] + ([("anchor", args.anchor)] if args.anchor else [])
        runs = {name: Runs() for name, _ in binaries}
        # They alternate, run by run, so a change of load on the shared machine falls on
        # all of them.
        for _ in range(args.runs):
            t, c = time.perf_counter(), time.process_time()
            d = Delatin(z, max_error=MAX_ERROR)
            delatin.append(time.perf_counter() - t)
            delatin_cpu.append(time.process_time() - c)
            for name, binary in binaries:
                runs[name].run(binary, asc, os.path.join(tmp, f"{name}.glb"), env)
        d_tris, d_err = len(d.triangles), d.error
        same = args.anchor and filecmp.cmp(
            os.path.join(tmp, "karstic.glb"), os.path.join(tmp, "anchor.glb"), shallow=False)

    med = statistics.median
    dm = med(delatin)
    print(machine_line())
    print(f"input: {N}x{N} spectral fBm (beta {BETA}, seed {SEED}), relief {RELIEF:.0f} m, "
          f"max error {MAX_ERROR} m, median of {args.runs} runs, one core")
    print(f"pydelatin  Delatin():           wall {dm:.3f} s  CPU {med(delatin_cpu):.3f} s  "
          f"{d_tris} triangles, max error {d_err:.3f} m")
    for name, binary in binaries:
        r = runs[name]
        km = med(r.triangulation)
        k_tris = int(re.search(r"(\d+) triangles", r.report).group(1))
        k_err = float(re.search(r"max error ([0-9.]+) m", r.report).group(1))
        print(f"{name:<10} tin, triangulation:  wall {km:.3f} s               "
              f"{k_tris} triangles, max error {k_err:.3f} m   ({binary})")
        print(f"{name:<10} tin, whole command:  wall {med(r.total):.3f} s  "
              f"CPU {med(r.cpu):.3f} s  (read .asc + triangulate + write .glb)")
        print(f"ratio pydelatin / {name} (triangulation, wall): {dm / km:.2f}x")
        print(f"ratio pydelatin / {name} (CPU, {name}'s whole command): "
              f"{med(delatin_cpu) / med(r.cpu):.2f}x")
    if args.anchor:
        ratio = med(runs["anchor"].triangulation) / med(runs["karstic"].triangulation)
        print(f"ratio anchor / karstic (triangulation, wall): {ratio:.2f}x")
        print(f"the two .glb files are {'byte-identical' if same else 'DIFFERENT'}")
    print(f"karstic: {runs['karstic'].report}")


class Runs:
    """One karstic binary's runs: the printed triangulation time, the whole command's
    wall and CPU time, and its last report."""

    def __init__(self):
        self.triangulation, self.total, self.cpu, self.report = [], [], [], ""

    def run(self, binary, asc, out, env):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        run = subprocess.run(
            [binary, "tin", asc, "-o", out, "--max-error", str(MAX_ERROR)],
            env=env, capture_output=True, text=True,
        )
        self.total.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
        if run.returncode != 0:
            sys.exit(f"{binary} tin failed:\n{run.stderr}")
        self.report = run.stderr.strip()
        self.triangulation.append(
            float(re.search(r"triangulation ([0-9.]+) s", self.report).group(1)))


if __name__ == "__main__":
    main()
