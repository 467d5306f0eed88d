"""Writes the synthetic DEMs of the landform scenes (ESRI ASCII grids, local metres).

sea_cliff.asc     a 35 m coastal plateau on a wavy coastline with two headlands,
                  dropping by a near-vertical cliff to a sea floor 12 m below sea level
                  (trees/sea_cliffs.ron).
karst_plateau.asc a 60 m limestone plateau ending in a cliff on its south side, with
                  five closed dolines 3-6 m deep where water sinks in
                  (trees/karst_network.ron).
badlands.asc      a 50 m plateau whose rim breaks into a concave badland slope, 36° under
                  the rim and flattening to a pediment 110 m out, cut by V-shaped gullies
                  about 28 m apart with sharp ridges between them (trees/hoodoo_field.ron).

`python3 trees/data/synthetic.py --big` also writes big_plateau.asc (not committed): a 5.2 km
plateau of 20 m cells with 120 dolines, the Fig. 17-scale karst of BENCHMARKS.md.

The files are written beside this script, wherever it is run from. Deterministic:
`python3 trees/data/synthetic.py` rewrites them byte for byte.
"""
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def write(path, nx, ny, cell, f):
    with open(os.path.join(HERE, path), "w") as out:
        out.write(f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\n")
        out.write(f"cellsize {cell}\nNODATA_value -9999\n")
        for r in range(ny):
            j = ny - 1 - r  # rows run north to south
            out.write(" ".join(f"{f(i * cell, j * cell):.2f}" for i in range(nx)) + "\n")


def smoothstep(a, b, x):
    t = min(max((x - a) / (b - a), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def cliff(x, y):
    coast = 110 + 22 * math.sin(x / 38.0) + 9 * math.sin(x / 11.0 + 1.0)
    land = 35 + 2.5 * math.sin(x / 17.0) * math.cos(y / 23.0) + 0.02 * (y - coast)
    sea = -12 + 0.05 * (y - coast)
    return sea + (land - sea) * smoothstep(coast - 2.5, coast + 2.5, y)


DOLINES = [(70, 250, 22, 5.0), (150, 300, 16, 4.0), (230, 220, 26, 6.0),
           (310, 310, 18, 3.5), (170, 160, 20, 4.5)]


def plateau(x, y):
    edge = 70 + 12 * math.sin(x / 45.0)
    top = 60 + 3 * math.sin(x / 60.0) * math.cos(y / 50.0)
    for (cx, cy, r, d) in DOLINES:
        q = ((x - cx) ** 2 + (y - cy) ** 2) / (r * r)
        if q < 1:
            top -= d * (1 - q) ** 2
    return 0.03 * y + top * smoothstep(edge - 6, edge + 6, y)


def badlands(x, y):
    rim = 150 + 8 * math.sin(x / 50.0) + 3 * math.sin(x / 13.0)
    top = 50 + 1.5 * math.sin(x / 40.0) * math.cos(y / 35.0) + 0.01 * (y - rim)
    d = rim - y
    if d <= 0:
        return top
    length = 110.0
    z = top * max(0.0, 1 - d / length) ** 1.6 + 0.02 * max(0.0, y)
    # Gullies: V-shaped cuts about 28 m apart, wandering down the slope, deepest at
    # mid-slope, dying out at the rim and on the pediment.
    phase = x / 28.0 + 0.35 * math.sin(y / 31.0) + 0.15 * math.sin(y / 9.0 + x / 17.0)
    u = abs(phase - math.floor(phase) - 0.5) * 28.0
    depth = 9.0 * smoothstep(0, 20, d) * (1 - smoothstep(length - 30, length + 5, d))
    return z - depth * max(0.0, 1 - u / 13.0) ** 1.3


write("sea_cliff.asc", 128, 128, 2, cliff)
write("karst_plateau.asc", 100, 100, 4, plateau)
write("badlands.asc", 160, 110, 2, badlands)


def big_plateau():
    rng = random.Random(5)
    dolines = [(rng.uniform(300, 4900), rng.uniform(900, 4900), rng.uniform(40, 90),
                rng.uniform(4, 9)) for _ in range(120)]

    def f(x, y):
        edge = 600 + 150 * math.sin(x / 450.0)
        top = 120 + 8 * math.sin(x / 600.0) * math.cos(y / 500.0)
        for (cx, cy, r, d) in dolines:
            q = ((x - cx) ** 2 + (y - cy) ** 2) / (r * r)
            if q < 1:
                top -= d * (1 - q) ** 2
        return 0.003 * y + top * smoothstep(edge - 40, edge + 40, y)
    return f


if "--big" in sys.argv:
    write("big_plateau.asc", 261, 261, 20, big_plateau())
