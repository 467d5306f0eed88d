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
"""

import argparse
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
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        asc = os.path.join(tmp, "fbm1025.asc")
        write_asc(asc, heightfield())
        # The samples exactly as written (three decimals), float32 as karstic reads them.
        z = np.loadtxt(asc, skiprows=6, dtype=np.float32)

        env = dict(os.environ, RAYON_NUM_THREADS="1")
        out = os.path.join(tmp, "tin.glb")
        delatin, delatin_cpu = [], []
        ours, totals, cpu_totals, report = [], [], [], ""
        # The two alternate, run by run, so a change of load on the shared machine
        # falls on both.
        for _ in range(args.runs):
            t, c = time.perf_counter(), time.process_time()
            d = Delatin(z, max_error=MAX_ERROR)
            delatin.append(time.perf_counter() - t)
            delatin_cpu.append(time.process_time() - c)

            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            run = subprocess.run(
                [args.karstic, "tin", asc, "-o", out, "--max-error", str(MAX_ERROR)],
                env=env, capture_output=True, text=True,
            )
            totals.append(time.perf_counter() - t)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu_totals.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
            if run.returncode != 0:
                sys.exit(f"karstic tin failed:\n{run.stderr}")
            report = run.stderr.strip()
            ours.append(float(re.search(r"triangulation ([0-9.]+) s", report).group(1)))
        d_tris, d_err = len(d.triangles), d.error
        k_tris = int(re.search(r"(\d+) triangles", report).group(1))
        k_err = float(re.search(r"max error ([0-9.]+) m", report).group(1))

    med = statistics.median
    dm, km = med(delatin), med(ours)
    print(machine_line())
    print(f"input: {N}x{N} spectral fBm (beta {BETA}, seed {SEED}), relief {RELIEF:.0f} m, "
          f"max error {MAX_ERROR} m, median of {args.runs} runs, one core")
    print(f"pydelatin  Delatin():           wall {dm:.3f} s  CPU {med(delatin_cpu):.3f} s  "
          f"{d_tris} triangles, max error {d_err:.3f} m")
    print(f"karstic    tin, triangulation:  wall {km:.3f} s               "
          f"{k_tris} triangles, max error {k_err:.3f} m")
    print(f"karstic    tin, whole command:  wall {med(totals):.3f} s  CPU {med(cpu_totals):.3f} s"
          "  (read .asc + triangulate + write .glb)")
    print(f"ratio pydelatin / karstic (triangulation, wall): {dm / km:.2f}x")
    print(f"ratio pydelatin / karstic (CPU, karstic's whole command): "
          f"{med(delatin_cpu) / med(cpu_totals):.2f}x")
    print(f"karstic: {report}")


if __name__ == "__main__":
    main()
