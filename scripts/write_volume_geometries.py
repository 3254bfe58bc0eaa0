#!/usr/bin/python3
"""Writes the volumes that knotwork's 3D cases and tests read from files, from their
mathematics, in both peer formats: GeoPDEs' geometry text v2.1 (cases/geometries/NAME.txt,
ndim = rdim = 3) and G+Smo's XML (cases/geometries/NAME.xml, TensorBSpline3/TensorNurbs3).

- thick_quarter_ring: the quarter annulus 1 <= r <= 2 in the first quadrant extruded to
  0 <= z <= 1, an exact NURBS volume (u along the radius, linear; v along the angle, a rational
  quadratic arc; w along z), with its faces labelled by where they lie: "inner" (r = 1), "outer"
  (r = 2), "symmetry" (the faces on x = 0 and y = 0), "base" (z = 0) and "lid" (z = 1). The XML
  has a MultiPatch (parDim 3) holding these labels.
- distorted_block: the image of the unit cube under the polynomial map
      F(u, v, w) = (u + v w / 5, v + u^2 / 4, w + u v / 10),
  written as a B-spline volume of degrees (2, 1, 1) with interior knots (u: 1/2; v: 1/3), so
  that the control points are not a regular grid and the directions have different counts. Its
  control points are the blossoms of F (polar forms) at the knots: exact, so a reader's numbering
  can be checked against F itself. The XML is a bare TensorBSpline3 (no MultiPatch).

Usage: scripts/write_volume_geometries.py [OUTPUT_DIRECTORY]   (default cases/geometries)
"""
import math
import os
import sys


def number(x):
    return repr(float(x))


class Volume:
    """Degrees p[3], knot vectors knots[3], control points cp[k][j][i] = (x, y, z), weights
    w[k][j][i] (u fastest in the files), and labelled faces {name: [face 1..6, ...]}."""

    def __init__(self, title, p, knots, cp, w, labels):
        self.title, self.p, self.knots, self.cp, self.w, self.labels = title, p, knots, cp, w, labels

    def counts(self):
        return [len(self.knots[d]) - self.p[d] - 1 for d in range(3)]

    def flat(self):
        """(point, weight) with u fastest, then v, then w."""
        nu, nv, nw = self.counts()
        return [(self.cp[k][j][i], self.w[k][j][i]) for k in range(nw) for j in range(nv) for i in range(nu)]

    def rational(self):
        return any(w != 1 for _, w in self.flat())


def thick_quarter_ring():
    s = math.sqrt(0.5)  # cos(pi/4): the middle weight of a quarter circle
    cp, w = [], []
    for z in (0.0, 1.0):
        rows, wrows = [], []
        # v = 0: the arc's start on the x axis; v = 1/2: the tangents' corner; v = 1: the y axis.
        for corner in ((1.0, 0.0), (1.0, 1.0), (0.0, 1.0)):
            rows.append([(r * corner[0], r * corner[1], z) for r in (1.0, 2.0)])
            wrows.append([s if corner == (1.0, 1.0) else 1.0] * 2)
        cp.append(rows)
        w.append(wrows)
    return Volume("thick quarter annulus 1 <= r <= 2, 0 <= z <= 1 (an exact NURBS volume)", [1, 2, 1],
                  [[0, 0, 1, 1], [0, 0, 0, 1, 1, 1], [0, 0, 1, 1]], cp, w,
                  {"inner": [1], "outer": [2], "symmetry": [3, 4], "base": [5], "lid": [6]})


def blossom_points(p, knots):
    """The arguments of the polar form of each B-spline coefficient: knots i+1 .. i+p."""
    return [knots[i + 1:i + 1 + p] for i in range(len(knots) - p - 1)]


def distorted_block():
    p = [2, 1, 1]
    knots = [[0, 0, 0, 0.5, 1, 1, 1], [0, 0, 1.0 / 3, 1, 1], [0, 0, 1, 1]]
    bu, bv, bw = (blossom_points(p[d], knots[d]) for d in range(3))

    def polar(a, b, c):
        # The blossom of F: u^2 -> a1 a2, u -> (a1 + a2) / 2 (degree 2 in u); v, w -> b1, c1.
        u1, u2 = a
        u = (u1 + u2) / 2
        return (u + b[0] * c[0] / 5, b[0] + u1 * u2 / 4, c[0] + u * b[0] / 10)

    cp = [[[polar(a, b, c) for a in bu] for b in bv] for c in bw]
    w = [[[1.0 for _ in bu] for _ in bv] for _ in bw]
    return Volume("the unit cube under F(u, v, w) = (u + v w / 5, v + u^2 / 4, w + u v / 10), a B-spline volume",
                  p, knots, cp, w, {})


def write_geopdes(path, v):
    with open(path, "w") as f:
        f.write("# %s\n# nurbs geometry v.2.1, written by knotwork's scripts/write_volume_geometries.py\n" % v.title)
        f.write("3 3 1\nPATCH 1\n%d %d %d\n%d %d %d\n" % (*v.p, *v.counts()))
        for k in v.knots:
            f.write(" ".join(number(t) for t in k) + "\n")
        points = v.flat()
        for c in range(3):  # weighted control points
            f.write(" ".join(number(w * x[c]) for x, w in points) + "\n")
        f.write(" ".join(number(w) for _, w in points) + "\n")
        for name, faces in v.labels.items():
            f.write("BOUNDARY %s\n%d\n" % (name, len(faces)))
            for face in faces:
                f.write("1 %d\n" % face)


def write_gismo(path, v):
    rational = v.rational()
    with open(path, "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n<!-- %s; written by knotwork\'s '
                'scripts/write_volume_geometries.py -->\n<xml>\n' % v.title)
        f.write(' <Geometry type="%s" id="0">\n' % ("TensorNurbs3" if rational else "TensorBSpline3"))
        if rational:
            f.write('  <Basis type="TensorNurbsBasis3">\n')
        f.write('  <Basis type="TensorBSplineBasis3">\n')
        for index in range(3):
            f.write('   <Basis type="BSplineBasis" index="%d">\n    <KnotVector degree="%d">%s</KnotVector>\n'
                    '   </Basis>\n' % (index, v.p[index], " ".join(number(t) for t in v.knots[index])))
        f.write("  </Basis>\n")
        points = v.flat()
        if rational:
            f.write("  <weights>%s</weights>\n  </Basis>\n" % " ".join(number(w) for _, w in points))
        f.write('  <coefs geoDim="3">\n')
        for x, _ in points:
            f.write("%s %s %s\n" % tuple(number(c) for c in x))
        f.write("  </coefs>\n </Geometry>\n")
        if v.labels:
            f.write(' <MultiPatch parDim="3" id="1">\n  <patches type="id_range">0 0</patches>\n')
            for name, faces in v.labels.items():
                f.write('  <boundary name="%s">\n' % name)
                for face in faces:
                    f.write("   0 %d\n" % face)
                f.write("  </boundary>\n")
            f.write(" </MultiPatch>\n")
        f.write("</xml>\n")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "cases", "geometries")
    os.makedirs(out, exist_ok=True)
    for name, build in (("thick_quarter_ring", thick_quarter_ring), ("distorted_block", distorted_block)):
        v = build()
        write_geopdes(os.path.join(out, name + ".txt"), v)
        write_gismo(os.path.join(out, name + ".xml"), v)
        print("%s: degrees %s, %s control points, labels %s" % (name, v.p, v.counts(), sorted(v.labels)))


if __name__ == "__main__":
    main()
