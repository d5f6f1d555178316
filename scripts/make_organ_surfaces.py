#!/usr/bin/python3
"""Writes scenes/meshes/liver.obj, a smooth liver-like organ surface (issue 26).

Not an ellipsoid cut from a lattice: a closed surface as a segmentation would give one, for the
mesher to fill with tets (`mesh: {surface: ...}`). The shape is star-shaped about its centre, so
it is built as a sphere whose radius varies smoothly with direction, which keeps it closed,
outward-oriented and free of self-intersections by construction:

  - base: an ellipsoid of semi-axes 80 x 55 x 34 mm (liver_palpation's lattice organ was 80 x 55 x 30);
  - the visceral (lower) face is flatter than the diaphragmatic (upper) dome: below the centre
    the vertical semi-axis shrinks to 80 %, and the centre is placed so that the lowest point
    stays 1 mm above z = 0 (the tray's top in the scene);
  - the left lobe (x < 0) tapers: thinner (to 55 %) and narrower (to 75 %) towards its tip;
  - a shallow notch in the front edge (y < 0) near x = 10 mm, as the gallbladder fossa.

Latitude rings from pole to pole (RINGS rings of SEGMENTS vertices, a vertex at each pole):
2 * SEGMENTS * (RINGS - 1) triangles. Metres; counter-clockwise seen from outside.

    /usr/bin/python3 scripts/make_organ_surfaces.py [OUTPUT]  (default scenes/meshes/liver.obj)

Deterministic: the same file every run. The output is written to a temporary name and renamed.
"""
import math
import os
import sys

RADII_M = (0.08, 0.055, 0.034)
LOWER_FLATTENING = 0.8
LEFT_THINNING = 0.45
LEFT_NARROWING = 0.25
NOTCH_DEPTH = 0.12
NOTCH_X_M = 0.01
NOTCH_WIDTH_M = 0.012
LOWEST_Z_M = 0.001
RINGS = 48
SEGMENTS = 96


def smoothstep(t):
    t = min(max(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def surface_point(theta, phi):
    """The point at polar angle theta (from +z) and azimuth phi, centre at the origin."""
    d = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))
    a, b, c = RADII_M
    x, y, z = a * d[0], b * d[1], c * d[2]
    if z < 0.0:
        z *= LOWER_FLATTENING
    left = smoothstep(-x / a)  # 0 at the middle, 1 at the left tip
    z *= 1.0 - LEFT_THINNING * left
    y *= 1.0 - LEFT_NARROWING * left
    if y < 0.0:
        notch = NOTCH_DEPTH * math.exp(-(((x - NOTCH_X_M) / NOTCH_WIDTH_M) ** 2))
        y *= 1.0 - notch * smoothstep(-y / b * 2.0)
    return (x, y, z)


def make_surface():
    vertices = [surface_point(0.0, 0.0)]
    for i in range(1, RINGS):
        theta = math.pi * i / RINGS
        for j in range(SEGMENTS):
            vertices.append(surface_point(theta, 2.0 * math.pi * j / SEGMENTS))
    vertices.append(surface_point(math.pi, 0.0))
    lift = LOWEST_Z_M - min(v[2] for v in vertices)
    vertices = [(x, y, z + lift) for x, y, z in vertices]

    def ring(i, j):  # 1-based OBJ index of vertex j of ring i (1 .. RINGS - 1)
        return 2 + (i - 1) * SEGMENTS + j % SEGMENTS

    south = len(vertices)
    triangles = []
    for j in range(SEGMENTS):
        triangles.append((1, ring(1, j), ring(1, j + 1)))
        for i in range(1, RINGS - 1):
            triangles.append((ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)))
            triangles.append((ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)))
        triangles.append((ring(RINGS - 1, j), south, ring(RINGS - 1, j + 1)))
    return vertices, triangles


def main():
    output = sys.argv[1] if len(sys.argv) > 1 else "scenes/meshes/liver.obj"
    vertices, triangles = make_surface()
    temporary = output + ".tmp"
    with open(temporary, "w") as f:
        f.write("# A liver-like organ surface: scripts/make_organ_surfaces.py (do not edit)\n")
        f.write("# %d vertices, %d triangles, metres\n" % (len(vertices), len(triangles)))
        for x, y, z in vertices:
            f.write("v %.9f %.9f %.9f\n" % (x, y, z))
        for a, b, c in triangles:
            f.write("f %d %d %d\n" % (a, b, c))
    os.replace(temporary, output)
    print("%s: %d vertices, %d triangles" % (output, len(vertices), len(triangles)))


if __name__ == "__main__":
    main()
