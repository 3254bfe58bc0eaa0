#!/usr/bin/env python3
"""Writes dodecahedron.obj: the regular dodecahedron with each pentagon split into five quads
(its centre, its corners and its edge midpoints), a closed quad mesh with vertices of valence
3 (the 20 corners), 4 (the 30 edge midpoints) and 5 (the 12 face centres). Projected onto a
sphere by the G1 cases ([geometry] shape = "sphere"); the symmetric gluing data there are
2cos(2 pi / 5) at the valence-5 vertices, irrational (docs/G1_POISSON.md).

    python3 cases/meshes/dodecahedron.py      # writes dodecahedron.obj here
"""
import itertools
import math
import os

from quad_meshes import Midpoints, write_obj

HERE = os.path.dirname(os.path.abspath(__file__))
PHI = (1 + 5 ** 0.5) / 2


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def main():
    corners = [tuple(float(s) for s in signs) for signs in itertools.product((-1, 1), repeat=3)]
    for a in (-1, 1):
        for b in (-1, 1):
            corners += [(0.0, a / PHI, b * PHI), (a / PHI, b * PHI, 0.0), (a * PHI, 0.0, b / PHI)]
    edge = 2 / PHI
    near = {i: [j for j in range(20) if j != i and abs(math.dist(corners[i], corners[j]) - edge) < 1e-9]
            for i in range(20)}
    # A face: the five corners nearest to the direction of a face centre (an icosahedron
    # vertex), i.e. the corners whose mean is that direction.
    faces = set()
    for i in range(20):
        for j in near[i]:
            for k in near[j]:
                if k == i:
                    continue
                normal = cross(sub(corners[j], corners[i]), sub(corners[k], corners[j]))
                ring = [l for l in range(20) if abs(dot(sub(corners[l], corners[i]), normal)) < 1e-9]
                if len(ring) == 5:
                    faces.add(tuple(sorted(ring)))
    assert len(faces) == 12
    vertices = list(corners)
    midpoint = Midpoints(vertices)

    quads = []
    for face in sorted(faces):
        centre = tuple(sum(corners[v][d] for v in face) / 5 for d in range(3))
        length = math.sqrt(dot(centre, centre))
        normal = tuple(x / length for x in centre)
        e1 = sub(corners[face[0]], centre)
        e2 = cross(normal, e1)
        ring = sorted(face, key=lambda v: math.atan2(dot(sub(corners[v], centre), e2), dot(sub(corners[v], centre), e1)))
        c = len(vertices)
        vertices.append(centre)
        for t in range(5):  # counter-clockwise seen from outside
            previous, here, following = ring[t - 1], ring[t], ring[(t + 1) % 5]
            quads.append((c, midpoint(previous, here), here, midpoint(here, following)))
    write_obj(os.path.join(HERE, "dodecahedron.obj"),
              ["The dodecahedron, each pentagon split into five quads: 62 vertices of valence 3 (20),",
               "4 (30) and 5 (12), 60 faces, outward. Written by dodecahedron.py."], vertices, quads)


if __name__ == "__main__":
    main()
