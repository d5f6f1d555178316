#!/usr/bin/python3
"""Writes the organ surfaces of the shipped scenes into scenes/meshes/ (issue 26): liver.obj,
kidney.obj and polyp.obj, smooth closed surfaces as a segmentation would give them, for the mesher
to fill with tets (`mesh: {surface: ...}`) and for the viewer to draw (`visual:`).

Each shape is star-shaped about its centre, so it is built as a sphere whose radius varies
smoothly with direction, which keeps it closed, outward-oriented and free of self-intersections
by construction. Latitude rings from pole to pole (`rings` rings of `segments` vertices, a vertex
at each pole): 2 * segments * (rings - 1) triangles. Metres; counter-clockwise seen from outside.
Each is lifted so that its lowest point lies at a given height (the tray's or wall's top + a gap).

liver (liver_palpation, two_organs): an ellipsoid of semi-axes 80 x 55 x 34 mm
  (liver_palpation's lattice organ was 80 x 55 x 30);
  - the visceral (lower) face is flatter than the diaphragmatic (upper) dome: below the centre
    the vertical semi-axis shrinks to 80 %; lowest point 1 mm above z = 0 (the tray's top);
  - the left lobe (x < 0) tapers: thinner (to 55 %) and narrower (to 75 %) towards its tip;
  - a shallow notch in the front edge (y < 0) near x = 10 mm, as the gallbladder fossa.
kidney (two_organs): a bean of semi-axes 55 x 30 x 22 mm, the hilum a notch 35 % deep in its
  medial (y < 0) side, its poles a little thinner; lowest point 1 mm above z = 0.
polyp (polyp): a sessile polyp, a dome of radii 4 x 4 x 6.5 mm on a broad base (below its centre
  the height shrinks to 60 %), with three shallow lobes around it (8 %) and a slight lean in x;
  lowest point 0.5 mm below z = 0, inside the cavity wall's fixed base region.

    /usr/bin/python3 scripts/make_organ_surfaces.py [FOLDER]   (default scenes/meshes)

Deterministic: the same files every run. Each is written to a temporary name and renamed.
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


def direction(theta, phi):
    """The unit vector at polar angle theta (from +z) and azimuth phi."""
    return (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))


def liver_point(theta, phi):
    """The liver's surface point in direction (theta, phi), centre at the origin."""
    d = direction(theta, phi)
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


KIDNEY_RADII_M = (0.055, 0.03, 0.022)
HILUM_DEPTH = 0.35
HILUM_WIDTH_M = 0.018
POLE_THINNING = 0.2


def kidney_point(theta, phi):
    """The kidney's surface point in direction (theta, phi), centre at the origin."""
    d = direction(theta, phi)
    a, b, c = KIDNEY_RADII_M
    x, y, z = a * d[0], b * d[1], c * d[2]
    z *= 1.0 - POLE_THINNING * (x / a) ** 2
    if y < 0.0:
        hilum = HILUM_DEPTH * math.exp(-((x / HILUM_WIDTH_M) ** 2))
        y *= 1.0 - hilum * smoothstep(-y / b * 1.5)
    return (x, y, z)


POLYP_RADII_M = (0.004, 0.004, 0.0065)
POLYP_BASE_FLATTENING = 0.6
POLYP_LOBES = 3
POLYP_LOBE_DEPTH = 0.08
POLYP_LEAN = 0.12


def polyp_point(theta, phi):
    """The polyp's surface point in direction (theta, phi), centre at the origin."""
    d = direction(theta, phi)
    a, b, c = POLYP_RADII_M
    lobes = 1.0 + POLYP_LOBE_DEPTH * math.cos(POLYP_LOBES * phi) * math.sin(theta) ** 2
    x, y, z = a * d[0] * lobes, b * d[1] * lobes, c * d[2]
    if z < 0.0:
        z *= POLYP_BASE_FLATTENING
    x += POLYP_LEAN * max(z, 0.0)  # the head leans a little towards +x
    return (x, y, z)


def make_surface(point, rings, segments, lowest_z_m):
    vertices = [point(0.0, 0.0)]
    for i in range(1, rings):
        theta = math.pi * i / rings
        for j in range(segments):
            vertices.append(point(theta, 2.0 * math.pi * j / segments))
    vertices.append(point(math.pi, 0.0))
    lift = lowest_z_m - min(v[2] for v in vertices)
    vertices = [(x, y, z + lift) for x, y, z in vertices]

    def ring(i, j):  # 1-based OBJ index of vertex j of ring i (1 .. rings - 1)
        return 2 + (i - 1) * segments + j % segments

    south = len(vertices)
    triangles = []
    for j in range(segments):
        triangles.append((1, ring(1, j), ring(1, j + 1)))
        for i in range(1, rings - 1):
            triangles.append((ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)))
            triangles.append((ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)))
        triangles.append((ring(rings - 1, j), south, ring(rings - 1, j + 1)))
    return vertices, triangles


# name: (surface point, rings, segments, lowest z in m, description)
ORGANS = {
    "liver": (liver_point, RINGS, SEGMENTS, LOWEST_Z_M, "A liver-like organ surface"),
    "kidney": (kidney_point, 40, 80, 0.001, "A kidney-like organ surface"),
    "polyp": (polyp_point, 32, 64, -0.0005, "A sessile polyp surface"),
}


def write_obj(path, title, vertices, triangles):
    temporary = path + ".tmp"
    with open(temporary, "w") as f:
        f.write("# %s: scripts/make_organ_surfaces.py (do not edit)\n" % title)
        f.write("# %d vertices, %d triangles, metres\n" % (len(vertices), len(triangles)))
        for x, y, z in vertices:
            f.write("v %.9f %.9f %.9f\n" % (x, y, z))
        for a, b, c in triangles:
            f.write("f %d %d %d\n" % (a, b, c))
    os.replace(temporary, path)


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else "scenes/meshes"
    for name, (point, rings, segments, lowest_z_m, title) in ORGANS.items():
        vertices, triangles = make_surface(point, rings, segments, lowest_z_m)
        path = os.path.join(folder, name + ".obj")
        write_obj(path, title, vertices, triangles)
        print("%s: %d vertices, %d triangles" % (path, len(vertices), len(triangles)))


if __name__ == "__main__":
    main()
