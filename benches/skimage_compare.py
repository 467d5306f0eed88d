#!/usr/bin/env python3
"""Marching Cubes throughput: karstic's dense path against scikit-image, same files.

Writes three 256^3 float32 grids (+ karstic sidecars) to benches/out/ -- a smooth blob,
a terrain-like heightfield with overhangs and caves, a dense gyroid -- then times
`skimage.measure.marching_cubes` (level 0.5, one core: it is single-threaded) and
`karstic build GRID.npy` (its `--stats` extraction time, RAYON_NUM_THREADS = 1 and 2) on
each file, and prints medians, M voxels/s and the ratios.

Usage: python3 benches/skimage_compare.py [--n 256] [--repeat 5]
Needs: numpy, scikit-image, and `cargo build --release` (uses target/release/karstic).
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from skimage import measure

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benches" / "out"
ISO = 0.5


def axes(n):
    t = np.linspace(-1.0, 1.0, n, dtype=np.float32)
    z, y, x = np.meshgrid(t, t, t, indexing="ij")  # shape (nz, ny, nx), C order
    return x, y, z


def blob(n):
    """A smooth blob: three Gaussian bumps, solid where > 0.5."""
    x, y, z = axes(n)
    f = np.zeros_like(x)
    for cx, cy, cz, r in [(-0.3, -0.1, 0.0, 0.45), (0.35, 0.1, 0.1, 0.4), (0.0, 0.3, -0.3, 0.35)]:
        f += np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (r * r))
    return f


def terrain(n):
    """Hills whose x is warped by z (overhangs) with two caves carved below the surface."""
    x, y, z = axes(n)
    xw = x + 0.12 * np.sin(7.0 * z + 2.0 * y)
    h = 0.25 * np.sin(3.0 * xw) * np.cos(2.0 * y) + 0.08 * np.sin(9.0 * xw + 5.0 * y)
    f = 0.5 + 2.0 * (h - z)
    for cx, cy, cz, r in [(-0.4, 0.2, -0.2, 0.25), (0.3, -0.3, -0.1, 0.2)]:
        d2 = ((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (r * r)
        f -= 1.5 * np.clip(1.0 - d2, 0.0, None) ** 3
    return f


def gyroid(n):
    """A dense gyroid: about 8 periods across the box."""
    x, y, z = axes(n)
    w = 8.0 * np.pi
    return ISO + (np.sin(w * x) * np.cos(w * y) + np.sin(w * y) * np.cos(w * z) + np.sin(w * z) * np.cos(w * x))


def write_grid(name, values):
    n = values.shape[0]
    path = OUT / f"{name}.npy"
    np.save(path, values.astype("<f4"))
    spacing = 2.0 / (n - 1)
    sidecar = {
        "shape": list(values.shape),
        "origin": [-1.0, -1.0, -1.0],
        "spacing": [spacing] * 3,
        "iso": ISO,
        "layout": "float32 C order, value[z][y][x] at origin + (x, y, z) * spacing",
    }
    (OUT / f"{name}.json").write_text(json.dumps(sidecar))
    return path


def time_skimage(path, repeat):
    vol = np.load(path)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        verts, faces, _normals, _values = measure.marching_cubes(vol, level=ISO)
        times.append(time.perf_counter() - t)
    return statistics.median(times), len(verts), len(faces)


def time_karstic(exe, path, threads, repeat):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    out = OUT / "karstic_out.ply"
    times, tris = [], 0
    for _ in range(repeat):
        r = subprocess.run([exe, "build", str(path), "-o", str(out), "--stats", "--quiet"],
                           env=env, capture_output=True, text=True, check=True)
        ms = re.search(r"time total\s+([\d.]+) ms", r.stdout)
        tris = int(re.search(r"triangles (\d+)", r.stdout).group(1))
        times.append(float(ms.group(1)) / 1e3)
    return statistics.median(times), tris


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--exe", default=str(ROOT / "target" / "release" / "karstic"))
    args = ap.parse_args()
    if not Path(args.exe).exists():
        sys.exit(f"{args.exe} not found: run `cargo build --release` first")
    OUT.mkdir(parents=True, exist_ok=True)
    voxels = args.n ** 3
    print(f"{args.n}^3 grids, median of {args.repeat}; M voxels/s = {voxels} / time / 1e6")
    print(f"{'grid':8} {'skimage 1c':>16} {'karstic 1c':>16} {'karstic 2c':>16} {'1c ratio':>9} {'2c ratio':>9}  triangles sk/ka")
    for name, make in [("blob", blob), ("terrain", terrain), ("gyroid", gyroid)]:
        path = write_grid(name, make(args.n))
        sk, _, sk_faces = time_skimage(path, args.repeat)
        k1, tris = time_karstic(args.exe, path, 1, args.repeat)
        k2, _ = time_karstic(args.exe, path, 2, args.repeat)
        mv = lambda t: voxels / t / 1e6
        print(f"{name:8} {sk*1e3:8.1f} ms {mv(sk):5.0f}M {k1*1e3:8.1f} ms {mv(k1):5.0f}M "
              f"{k2*1e3:8.1f} ms {mv(k2):5.0f}M {sk/k1:8.2f}x {sk/k2:8.2f}x  {sk_faces}/{tris}")


if __name__ == "__main__":
    main()
