#!/usr/bin/python3
"""Writes scenes/meshes/probe_surface.obj, the rigid bumpy plate of scenes/probe.yaml.

A closed slab 40 x 40 mm, its top a height field of 22 x 22 cells (968 triangles) over a 5 mm
thick base: a smooth bump of 3 mm (a raised cosine, 20 mm across) in the middle and a ripple of
0.3 mm amplitude and 8 mm wavelength along x, so that a point probe stroked across it meets
slopes, a crest and curvature on a mesh of about a thousand triangles (paper 004 renders about
1,000 surfaces at 1 kHz). Sides and a bottom fan close it: 1,232 triangles in all. Metres; the top's
flat level is z = 0 in its frame, the bottom z = -5 mm. Counter-clockwise seen from outside.

    /usr/bin/python3 scripts/make_probe_surface.py [OUTPUT]  (default scenes/meshes/probe_surface.obj)

Deterministic: the same file every run. The output is written to a temporary name and renamed.
"""
import math
import os
import sys

SIZE_M = 0.04
CELLS = 22
BASE_M = 0.005
BUMP_HEIGHT_M = 0.003
BUMP_RADIUS_M = 0.01
RIPPLE_M = 0.0003
RIPPLE_WAVELENGTH_M = 0.008


def height(x, y):
    r = math.hypot(x, y)
    bump = 0.5 * BUMP_HEIGHT_M * (1.0 + math.cos(math.pi * r / BUMP_RADIUS_M)) if r < BUMP_RADIUS_M else 0.0
    return bump + RIPPLE_M * math.sin(2.0 * math.pi * x / RIPPLE_WAVELENGTH_M)


def make_surface():
    n = CELLS
    h = SIZE_M / n
    coordinate = [-0.5 * SIZE_M + i * h for i in range(n + 1)]
    vertices, triangles = [], []
    top = {}
    bottom = {}
    for i in range(n + 1):
        for j in range(n + 1):
            x, y = coordinate[i], coordinate[j]
            top[(i, j)] = len(vertices)
            vertices.append((x, y, height(x, y)))
    for i in range(n + 1):
        for j in range(n + 1):
            if i in (0, n) or j in (0, n):
                bottom[(i, j)] = len(vertices)
                vertices.append((coordinate[i], coordinate[j], -BASE_M))
    for i in range(n):
        for j in range(n):  # top: counter-clockwise seen from +z
            a, b, c, d = top[(i, j)], top[(i + 1, j)], top[(i + 1, j + 1)], top[(i, j + 1)]
            triangles += [(a, b, c), (a, c, d)]
    # Sides: the boundary ring of the top, walked counter-clockwise seen from +z, each edge
    # joined to the bottom ring below it.
    ring = [(i, 0) for i in range(n)] + [(n, j) for j in range(n)] + \
           [(i, n) for i in range(n, 0, -1)] + [(0, j) for j in range(n, 0, -1)]
    for k in range(len(ring)):
        p, q = ring[k], ring[(k + 1) % len(ring)]
        triangles += [(top[p], bottom[p], bottom[q]), (top[p], bottom[q], top[q])]
    # Bottom: a fan over its ring (a convex square), counter-clockwise seen from -z.
    centre = len(vertices)
    vertices.append((0.0, 0.0, -BASE_M))
    for k in range(len(ring)):
        p, q = ring[k], ring[(k + 1) % len(ring)]
        triangles.append((centre, bottom[q], bottom[p]))
    return vertices, triangles


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    output = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "scenes/meshes/probe_surface.obj")
    vertices, triangles = make_surface()
    temporary = output + ".tmp"
    with open(temporary, "w") as f:
        f.write("# Bumpy plate of scenes/probe.yaml, made by scripts/make_probe_surface.py; metres.\n")
        for v in vertices:
            f.write("v %.9f %.9f %.9f\n" % v)
        for t in triangles:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    os.replace(temporary, output)
    print("%s: %d vertices, %d triangles" % (output, len(vertices), len(triangles)))


if __name__ == "__main__":
    main()
