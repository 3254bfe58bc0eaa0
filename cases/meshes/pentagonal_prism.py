#!/usr/bin/env python3
"""Writes pentagonal_prism.obj: the pentagonal prism with every face split into quads (its
centre, its corners and its edge midpoints), a closed quad mesh with vertices of valence 3
(the 10 corners), 4 (the 15 edge midpoints and the 5 rectangle centres) and 5 (the 2
pentagon centres). At the midpoint of a pentagon's edge the two neighbours across are a
pentagon centre (valence 5) and a rectangle centre (valence 4): the linear symmetric gluing
data fail Condition 3.2 there, and the analysis-suitable construction gives those crossings
a skewed fan (docs/G1_POISSON.md). Projected onto a sphere by the G1 cases ([geometry] shape =
"sphere").

    python3 cases/meshes/pentagonal_prism.py      # writes pentagonal_prism.obj here
"""
import math
import os

from quad_meshes import split_faces, write_obj

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    # Corners on the unit sphere: two pentagons at heights +-h, h chosen so that the side
    # rectangles are squares on the sphere's scale (side of the pentagon = 2h).
    side = 2 * math.sin(math.pi / 5)
    h = side / 2
    scale = 1 / math.sqrt(1 + h * h)
    top = [(scale * math.cos(2 * math.pi * i / 5), scale * math.sin(2 * math.pi * i / 5), scale * h) for i in range(5)]
    bottom = [(x, y, -z) for x, y, z in top]
    vertices = top + bottom
    # Faces counter-clockwise seen from outside.
    faces = [list(range(5)), [5 + i for i in reversed(range(5))]]
    faces += [[i, 5 + i, 5 + (i + 1) % 5, (i + 1) % 5] for i in range(5)]
    quads = split_faces(vertices, faces)
    write_obj(os.path.join(HERE, "pentagonal_prism.obj"),
              ["The pentagonal prism, each face split into quads: %d vertices of valence 3 (10)," % len(vertices),
               "4 (20) and 5 (2), %d faces, outward. Written by pentagonal_prism.py." % len(quads)], vertices, quads)


if __name__ == "__main__":
    main()
