#!/usr/bin/env python3
"""Writes pentagonal_antiprism.obj: the pentagonal antiprism with every face split into quads
(its centre, its corners and its edge midpoints), a closed quad mesh with vertices of valence
3 (the 10 triangle centres), 4 (the 10 corners and the 20 edge midpoints) and 5 (the 2
pentagon centres). At the midpoint of an edge between a triangle and a pentagon the
neighbours across are a triangle centre (3) and a pentagon centre (5): the linear symmetric
gluing data fail Condition 3.2 there; once those crossings get a skewed fan, the corners next
to them fail in turn and are skewed too (docs/G1_POISSON.md). Projected onto a sphere by the
G1 cases ([geometry] shape = "sphere").

    python3 cases/meshes/pentagonal_antiprism.py      # writes pentagonal_antiprism.obj here
"""
import math
import os

from quad_meshes import split_faces, write_obj

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    n, h = 5, 0.5
    vertices = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), h) for i in range(n)]
    vertices += [(math.cos(2 * math.pi * (i + 0.5) / n), math.sin(2 * math.pi * (i + 0.5) / n), -h) for i in range(n)]

    def outward(face):
        """The face's corners counter-clockwise seen from outside (the mesh is convex)."""
        a, b, c = (vertices[i] for i in face[:3])
        u = [b[d] - a[d] for d in range(3)]
        w = [c[d] - a[d] for d in range(3)]
        normal = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        centre = [sum(vertices[i][d] for i in face) / len(face) for d in range(3)]
        return face if sum(x * y for x, y in zip(normal, centre)) > 0 else face[::-1]

    faces = [outward(list(range(n))), outward([n + i for i in range(n)])]
    for i in range(n):
        faces.append(outward([i, n + i, (i + 1) % n]))
        faces.append(outward([n + i, n + (i + 1) % n, (i + 1) % n]))
    quads = split_faces(vertices, faces)
    write_obj(os.path.join(HERE, "pentagonal_antiprism.obj"),
              ["The pentagonal antiprism, each face split into quads: %d vertices of valence 3 (10)," % len(vertices),
               "4 (30) and 5 (2), %d faces, outward. Written by pentagonal_antiprism.py." % len(quads)], vertices, quads)


if __name__ == "__main__":
    main()
