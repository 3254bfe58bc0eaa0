#!/usr/bin/env python3
"""Writes the planar quad meshes made by splitting triangles (each triangle into three quads
at its centroid and edge midpoints): a vertex shared by n triangles gets valence n, each
centroid valence 3, each interior edge midpoint valence 4. Every quad is convex when the
triangle is. Coordinates are multiples of 1/64 (midpoints and centroids rounded to them).

    python3 cases/meshes/split_triangles.py      # writes valences_6_8.obj and lshape_split.obj here
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def snap(x):
    return round(x * 64) / 64


def split(points, triangles, header):
    """OBJ text: points (x, y), counter-clockwise triangles (i, j, k) of them."""
    vertices, index = [], {}

    def vid(p):
        p = (snap(p[0]), snap(p[1]))
        if p not in index:
            index[p] = len(vertices) + 1
            vertices.append(p)
        return index[p]

    def mid(a, b):
        return ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)

    faces = []
    for t in triangles:
        a, b, c = (points[i] for i in t)
        g = ((a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3)
        for x, y, z in ((a, b, c), (b, c, a), (c, a, b)):
            faces.append((vid(x), vid(mid(x, y)), vid(g), vid(mid(z, x))))
    lines = ["# " + line for line in header] + ["v %s %s 0" % (repr(x), repr(y)) for x, y in vertices]
    lines += ["f %d %d %d %d" % f for f in faces]
    return "\n".join(lines) + "\n"


def valences_6_8():
    # Two interior vertices P (8 triangles around it) and Q (6), inside a polygon on the
    # circle of radius 2: P's fan takes the left half in steps of 30 degrees, Q's the right half
    # in steps of 45, and two triangles share the edge PQ.
    P, Q = (-0.5, 0.0), (0.5, 0.0)
    ring = lambda deg: (2 * math.cos(math.radians(deg)), 2 * math.sin(math.radians(deg)))
    left = [ring(d) for d in range(90, 271, 30)]  # 90 .. 270: 7 points
    right = [ring(d) for d in (270, 315, 360, 45, 90)]
    points = [P, Q] + left + right[1:-1]
    top, bottom = 2, 2 + len(left) - 1
    tris = [(0, 2 + i, 3 + i) for i in range(len(left) - 1)]  # P's fan, counter-clockwise
    right_ids = [bottom] + list(range(2 + len(left), len(points))) + [top]
    tris += [(1, right_ids[i], right_ids[i + 1]) for i in range(len(right_ids) - 1)]
    tris += [(0, bottom, 1), (0, 1, top)]
    return split(points, tris, ["A polygon inscribed in the circle of radius 2, 12 triangles split into 36 quads:",
                                "interior vertices of valence 8 (at (-0.5, 0)), 6 (at (0.5, 0)), 3 and 4.",
                                "Written by split_triangles.py."])


def lshape_split():
    # The L-shape [-1, 1]^2 minus [0, 1] x [-1, 0], cut into triangles around three interior
    # points: the re-entrant corner gets valence 5, the interior points 5 and 6.
    pts = [(-1, -1), (0, -1), (0, 0), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0),
           (-0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)]
    tris = [(0, 1, 8), (1, 2, 8), (2, 9, 8), (8, 9, 7), (0, 8, 7),
            (2, 3, 10), (3, 4, 10), (4, 5, 10), (5, 9, 10), (2, 10, 9), (5, 6, 9), (6, 7, 9)]
    return split(pts, tris, ["The L-shape [-1, 1]^2 minus [0, 1] x [-1, 0]: 12 triangles split into 36 quads,",
                             "interior vertices of valence 3, 4, 5 and 6, the re-entrant corner of valence 5.",
                             "Written by split_triangles.py."])


if __name__ == "__main__":
    for name, text in (("valences_6_8.obj", valences_6_8()), ("lshape_split.obj", lshape_split())):
        with open(os.path.join(HERE, name), "w") as f:
            f.write(text)
