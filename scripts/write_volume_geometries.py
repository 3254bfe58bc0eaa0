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

- fichera_7patches: the Fichera corner (-1,1)^3 less the octant [0,1]^3 as seven unit cubes,
  trilinear, glued face to face. Three of them have their parameter directions permuted or
  reversed against x, y, z, so that the interfaces exercise every kind of orientation the
  formats carry (GeoPDEs' "flag ornt1 ornt2", G+Smo's direction map and orientation flags). The
  interfaces are found here by matching the cubes' faces point for point; the faces that bound
  the removed octant are labelled "reentrant", the others "outer".

Usage: scripts/write_volume_geometries.py [OUTPUT_DIRECTORY]   (default cases/geometries)
"""
import argparse
import math
import os


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


class Cube:
    """The unit cube at `origin` (its lowest corner), parameter direction d along the physical
    axis axis[d], increasing when sign[d] = 1 and decreasing when -1."""

    def __init__(self, origin, axis, sign):
        self.origin, self.axis, self.sign = origin, axis, sign

    def point(self, t):
        x = list(self.origin)
        for d in range(3):
            a = self.axis[d]
            x[a] += t[d] if self.sign[d] == 1 else 1 - t[d]
        return tuple(float(c) for c in x)

    def volume(self):
        cp = [[[self.point((i, j, k)) for i in (0, 1)] for j in (0, 1)] for k in (0, 1)]
        w = [[[1.0, 1.0] for _ in (0, 1)] for _ in (0, 1)]
        return Volume("", [1, 1, 1], [[0, 0, 1, 1]] * 3, cp, w, {})


def face_frame(face):
    """Face 1..6: its normal direction, its value (0 or 1), and its two free directions in the
    order u, v, w."""
    normal = (face - 1) // 2
    free = [d for d in range(3) if d != normal]
    return normal, (face - 1) % 2, free


def face_point(cube, face, s, t):
    normal, value, (first, second) = face_frame(face)
    x = [0.0, 0.0, 0.0]
    x[normal], x[first], x[second] = value, s, t
    return cube.point(x)


def match(a, fa, b, fb):
    """How face fa of cube a is face fb of cube b: (same_order, reverse_first, reverse_second),
    or None. The corners decide (the cubes are trilinear)."""
    for same in (True, False):
        for r1 in (False, True):
            for r2 in (False, True):
                def on_b(s, t):
                    first, second = (1 - s if r1 else s), (1 - t if r2 else t)
                    return (first, second) if same else (second, first)
                if all(face_point(a, fa, s, t) == face_point(b, fb, *on_b(s, t)) for s in (0, 1) for t in (0, 1)):
                    return same, r1, r2
    return None


def fichera_cubes():
    cubes = []
    for z in (-1, 0):
        for y in (-1, 0):
            for x in (-1, 0):
                if (x, y, z) != (0, 0, 0):
                    cubes.append(Cube((x, y, z), [0, 1, 2], [1, 1, 1]))
    # Turned cubes: parameters permuted and reversed against x, y, z, each still a right-handed
    # frame (det J > 0, which knotwork requires).
    cubes[1] = Cube(cubes[1].origin, [1, 0, 2], [1, -1, 1])    # u along y, v against x
    cubes[4] = Cube(cubes[4].origin, [2, 1, 0], [-1, 1, 1])    # u against z, w along x
    cubes[6] = Cube(cubes[6].origin, [1, 2, 0], [1, -1, -1])   # u along y, v against z, w against x
    interfaces, boundary = [], {"reentrant": [], "outer": []}
    for p, a in enumerate(cubes):
        for fa in range(1, 7):
            glued = False
            for q, b in enumerate(cubes):
                if q == p:
                    continue
                for fb in range(1, 7):
                    m = match(a, fa, b, fb)
                    if m:
                        glued = True
                        if p < q:
                            interfaces.append((p, fa, q, fb, m))
            if not glued:
                centre = face_point(a, fa, 0.5, 0.5)
                on_octant = sum(1 for c in centre if c == 0) == 1 and all(c >= 0 for c in centre)
                boundary["reentrant" if on_octant else "outer"].append((p, fa))
    return cubes, interfaces, boundary


def gismo_direction_map(a, fa, b, fb, m):
    """G+Smo's direction map and orientation flags of an interface: direction k of cube a goes
    to direction map[k] of cube b, running the same way when flag[k] = 1."""
    direction = [0, 0, 0]
    flags = [1, 1, 1]
    for k in range(3):
        axis = a.axis[k]
        direction[k] = b.axis.index(axis)
        flags[k] = 1 if a.sign[k] == b.sign[direction[k]] else 0
    return direction, flags


def write_fichera(out):
    cubes, interfaces, boundary = fichera_cubes()
    title = "the Fichera corner (-1,1)^3 less the octant [0,1]^3 as seven unit cubes, three of them turned"
    path = os.path.join(out, "fichera_7patches.txt")
    with open(path, "w") as f:
        f.write("# %s\n# nurbs geometry v.2.1, written by knotwork's scripts/write_volume_geometries.py\n" % title)
        f.write("3 3 %d %d 0\n" % (len(cubes), len(interfaces)))
        for n, c in enumerate(cubes):
            v = c.volume()
            f.write("PATCH %d\n1 1 1\n2 2 2\n" % (n + 1))
            for k in v.knots:
                f.write(" ".join(number(t) for t in k) + "\n")
            points = v.flat()
            for d in range(3):
                f.write(" ".join(number(w * x[d]) for x, w in points) + "\n")
            f.write(" ".join(number(w) for _, w in points) + "\n")
        for n, (p, fa, q, fb, (same, r1, r2)) in enumerate(interfaces):
            f.write("INTERFACE %d\n%d %d\n%d %d\n%d %d %d\n" % (n + 1, p + 1, fa, q + 1, fb, 1 if same else -1,
                                                               -1 if r1 else 1, -1 if r2 else 1))
        for name in ("reentrant", "outer"):
            f.write("BOUNDARY %s\n%d\n" % (name, len(boundary[name])))
            for p, face in boundary[name]:
                f.write("%d %d\n" % (p + 1, face))
    path = os.path.join(out, "fichera_7patches.xml")
    with open(path, "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n<!-- %s; written by knotwork\'s '
                'scripts/write_volume_geometries.py -->\n<xml>\n' % title)
        for n, c in enumerate(cubes):
            v = c.volume()
            f.write(' <Geometry type="TensorBSpline3" id="%d">\n  <Basis type="TensorBSplineBasis3">\n' % n)
            for index in range(3):
                f.write('   <Basis type="BSplineBasis" index="%d">\n    <KnotVector degree="1">0 0 1 1</KnotVector>\n'
                        '   </Basis>\n' % index)
            f.write('  </Basis>\n  <coefs geoDim="3">\n')
            for x, _ in v.flat():
                f.write("%s %s %s\n" % tuple(number(c) for c in x))
            f.write("  </coefs>\n </Geometry>\n")
        f.write(' <MultiPatch parDim="3" id="100">\n  <patches type="id_range">0 %d</patches>\n  <interfaces>\n' % (len(cubes) - 1))
        for p, fa, q, fb, m in interfaces:
            direction, flags = gismo_direction_map(cubes[p], fa, cubes[q], fb, m)
            f.write("   %d %d %d %d %s %s\n" % (p, fa, q, fb, " ".join(map(str, direction)), " ".join(map(str, flags))))
        f.write("  </interfaces>\n")
        for name in ("reentrant", "outer"):
            f.write('  <boundary name="%s">\n' % name)
            for p, face in boundary[name]:
                f.write("   %d %d\n" % (p, face))
            f.write("  </boundary>\n")
        f.write(" </MultiPatch>\n</xml>\n")
    print("fichera_7patches: %d cubes, %d interfaces, %d re-entrant and %d outer faces" %
          (len(cubes), len(interfaces), len(boundary["reentrant"]), len(boundary["outer"])))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", nargs="?", default=os.path.join(os.path.dirname(__file__), "..", "cases", "geometries"),
                        help="the folder to write into (default: cases/geometries)")
    out = parser.parse_args().out
    os.makedirs(out, exist_ok=True)
    for name, build in (("thick_quarter_ring", thick_quarter_ring), ("distorted_block", distorted_block)):
        v = build()
        write_geopdes(os.path.join(out, name + ".txt"), v)
        write_gismo(os.path.join(out, name + ".xml"), v)
        print("%s: degrees %s, %s control points, labels %s" % (name, v.p, v.counts(), sorted(v.labels)))
    write_fichera(out)


if __name__ == "__main__":
    main()
