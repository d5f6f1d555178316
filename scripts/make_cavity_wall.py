#!/usr/bin/python3
"""Writes scenes/meshes/cavity_wall.obj, the rigid cavity wall of scenes/polyp.yaml.

The wall is a curved shell: the part of a thick-walled tube (axis x, inner radius 15 mm, 3 mm
thick, 30 mm long) within 70 degrees either side of straight down, like the floor of a uterine
cavity seen through a hysteroscope. It is a closed, outward-oriented triangle mesh in metres
(hapsim reads rigid meshes with the pseudonormal signed distance, exact for such a mesh, concave
or not), its frame on the tube's axis: the inner surface's lowest line is at z = -15 mm.

    /usr/bin/python3 scripts/make_cavity_wall.py [OUTPUT]    (default scenes/meshes/cavity_wall.obj)

Deterministic: the same file every run. The output is written to a temporary name and renamed.
"""
import math
import os
import sys

INNER_RADIUS_M = 0.015
OUTER_RADIUS_M = 0.018
LENGTH_M = 0.03
HALF_ANGLE_RAD = math.radians(70.0)
SEGMENTS = 16  # around the arc: a chord's sagitta is R (1 - cos(dphi/2)) = 0.04 mm inside


def vertex(x, radius, phi):
    """Point at axial position x, distance `radius` from the axis, angle phi from straight down."""
    return (x, radius * math.sin(phi), -radius * math.cos(phi))


def make_wall():
    vertices, triangles = [], []
    index = {}
    half = 0.5 * LENGTH_M
    for k in range(SEGMENTS + 1):
        phi = -HALF_ANGLE_RAD + 2.0 * HALF_ANGLE_RAD * k / SEGMENTS
        for end, x in enumerate((-half, half)):
            for layer, radius in enumerate((INNER_RADIUS_M, OUTER_RADIUS_M)):
                index[(k, end, layer)] = len(vertices)
                vertices.append(vertex(x, radius, phi))

    def quad(a, b, c, d, outward):
        """Two triangles of quad a-b-c-d, each turned so that its normal points along `outward`."""
        for tri in ((a, b, c), (a, c, d)):
            p = [vertices[i] for i in tri]
            u = [p[1][j] - p[0][j] for j in range(3)]
            v = [p[2][j] - p[0][j] for j in range(3)]
            n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
            if sum(n[j] * outward[j] for j in range(3)) < 0.0:
                tri = (tri[0], tri[2], tri[1])
            triangles.append(tri)

    for k in range(SEGMENTS):
        phi = -HALF_ANGLE_RAD + 2.0 * HALF_ANGLE_RAD * (k + 0.5) / SEGMENTS
        radial = (0.0, math.sin(phi), -math.cos(phi))
        inward = tuple(-c for c in radial)
        # Inner surface (facing the axis) and outer surface (facing away).
        quad(index[(k, 0, 0)], index[(k, 1, 0)], index[(k + 1, 1, 0)], index[(k + 1, 0, 0)], inward)
        quad(index[(k, 0, 1)], index[(k, 1, 1)], index[(k + 1, 1, 1)], index[(k + 1, 0, 1)], radial)
        # The two end faces, across the wall's thickness.
        for end, outward in ((0, (-1.0, 0.0, 0.0)), (1, (1.0, 0.0, 0.0))):
            quad(index[(k, end, 0)], index[(k, end, 1)], index[(k + 1, end, 1)],
                 index[(k + 1, end, 0)], outward)
    # The two long edges of the shell, where the arc ends.
    for k, sign in ((0, -1.0), (SEGMENTS, 1.0)):
        phi = -HALF_ANGLE_RAD + 2.0 * HALF_ANGLE_RAD * k / SEGMENTS
        tangent = (0.0, sign * math.cos(phi), sign * math.sin(phi))
        quad(index[(k, 0, 0)], index[(k, 1, 0)], index[(k, 1, 1)], index[(k, 0, 1)], tangent)
    return vertices, triangles


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    output = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "scenes/meshes/cavity_wall.obj")
    vertices, triangles = make_wall()
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    temporary = output + ".tmp"
    with open(temporary, "w") as f:
        f.write("# Cavity wall of scenes/polyp.yaml, made by scripts/make_cavity_wall.py; metres.\n")
        for v in vertices:
            f.write("v %.9f %.9f %.9f\n" % v)
        for t in triangles:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    os.replace(temporary, output)
    print("%s: %d vertices, %d triangles" % (output, len(vertices), len(triangles)))


if __name__ == "__main__":
    main()
