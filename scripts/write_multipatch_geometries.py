#!/usr/bin/python3
"""Writes the multipatch geometries that knotwork's cases use, from their mathematics, in both
peer formats: GeoPDEs' geometry text v2.1 (cases/geometries/NAME.txt) and G+Smo's XML
(cases/geometries/NAME.xml).

Every patch here is one rational Bezier patch (open knots, no interior knot). The interfaces
and their orientations are found by comparing the patches' sides (ends and midpoint), and every
other side is a boundary side, labelled by the rule of its domain. Some patches are written
reversed or transposed on purpose, so that the files exercise the orientation of interfaces.

Usage: scripts/write_multipatch_geometries.py [OUTPUT_DIRECTORY]   (default cases/geometries)
"""
import argparse
import math
import os

import numpy as np


def binom(n, k):
    return math.comb(n, k)


class Patch:
    """Control points cp[j][i] (i along u), weights w[j][i], degrees (p, q)."""

    def __init__(self, cp, w=None):
        self.cp = np.asarray(cp, dtype=float)
        self.w = np.ones(self.cp.shape[:2]) if w is None else np.asarray(w, dtype=float)
        self.q, self.p = self.cp.shape[0] - 1, self.cp.shape[1] - 1

    def point(self, u, v):
        bu = np.array([binom(self.p, a) * u**a * (1 - u) ** (self.p - a) for a in range(self.p + 1)])
        bv = np.array([binom(self.q, b) * v**b * (1 - v) ** (self.q - b) for b in range(self.q + 1)])
        weights = np.outer(bv, bu) * self.w
        return (weights[:, :, None] * self.cp).sum(axis=(0, 1)) / weights.sum()

    def reversed_u(self):
        return Patch(self.cp[:, ::-1], self.w[:, ::-1])

    def transposed(self):
        return Patch(self.cp.transpose(1, 0, 2), self.w.T)

    def turned(self, quarters=1):
        """The same patch with its parameter square turned by quarter turns (orientation kept)."""
        p = self
        for _ in range(quarters):
            p = p.transposed().reversed_u()
        return p


# Side s in the files' numbering: the parameters of the point at t along it.
SIDES = {1: lambda t: (0.0, t), 2: lambda t: (1.0, t), 3: lambda t: (t, 0.0), 4: lambda t: (t, 1.0)}


def side_points(patch, s):
    return [patch.point(*SIDES[s](t)) for t in (0.0, 0.5, 1.0)]


def topology(patches, label_of_side):
    """Interfaces (pa, sa, pb, sb, reversed) and labelled boundary sides, from the geometry."""
    scale = max(np.ptp(np.concatenate([p.cp.reshape(-1, 2) for p in patches]), axis=0))
    close = lambda a, b: np.linalg.norm(a - b) < 1e-12 * scale
    interfaces, used, boundary = [], set(), {}
    for a, pa in enumerate(patches):
        for sa in range(1, 5):
            if (a, sa) in used:
                continue
            xa = side_points(pa, sa)
            for b, pb in enumerate(patches):
                for sb in range(1, 5):
                    if (b, sb) in used or (a, sa) == (b, sb):
                        continue
                    xb = side_points(pb, sb)
                    if all(close(x, y) for x, y in zip(xa, xb)):
                        interfaces.append((a, sa, b, sb, False))
                    elif all(close(x, y) for x, y in zip(xa, xb[::-1])):
                        interfaces.append((a, sa, b, sb, True))
                    else:
                        continue
                    used.update({(a, sa), (b, sb)})
                    break
                if (a, sa) in used:
                    break
            if (a, sa) not in used:
                boundary.setdefault(label_of_side(xa[1]), []).append((a, sa))
    return interfaces, boundary


def number(x):
    return repr(float(x))


def write_geopdes(path, title, patches, interfaces, boundary):
    with open(path, "w") as f:
        f.write("# %s\n# nurbs geometry v.2.1, written by knotwork's scripts/write_multipatch_geometries.py\n" % title)
        f.write("2 2 %d %d 1\n" % (len(patches), len(interfaces)))
        for k, p in enumerate(patches):
            f.write("PATCH %d\n%d %d\n%d %d\n" % (k + 1, p.p, p.q, p.p + 1, p.q + 1))
            for d in (p.p, p.q):
                f.write(" ".join(["0.0"] * (d + 1) + ["1.0"] * (d + 1)) + "\n")
            for c in range(2):  # weighted control points, u fastest
                f.write(" ".join(number(p.w[j, i] * p.cp[j, i, c]) for j in range(p.q + 1) for i in range(p.p + 1)) + "\n")
            f.write(" ".join(number(p.w[j, i]) for j in range(p.q + 1) for i in range(p.p + 1)) + "\n")
        for k, (a, sa, b, sb, rev) in enumerate(interfaces):
            f.write("INTERFACE %d\n%d %d\n%d %d\n%d\n" % (k + 1, a + 1, sa, b + 1, sb, -1 if rev else 1))
        f.write("SUBDOMAIN 1\n" + " ".join(str(k + 1) for k in range(len(patches))) + "\n")
        for name, sides in boundary.items():
            f.write("BOUNDARY %s\n%d\n" % (name, len(sides)))
            for a, s in sides:
                f.write("%d %d\n" % (a + 1, s))


def write_gismo(path, title, patches, interfaces, boundary, problem=None):
    """The domain as G+Smo XML; with `problem` (XML text of functions and boundary conditions),
    a G+Smo problem file laid out as G+Smo's pde/ examples are: the MultiPatch has id 0 and the
    patches ids from 100, leaving 1..4 to the source, conditions, exact solution and options."""
    first_id, multipatch_id = (100, 0) if problem else (0, len(patches))
    with open(path, "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n<!-- %s; written by knotwork\'s '
                'scripts/write_multipatch_geometries.py -->\n<xml>\n' % title)
        for k, p in enumerate(patches):
            rational = bool((p.w != 1).any())
            f.write(' <Geometry type="%s" id="%d">\n' % ("TensorNurbs2" if rational else "TensorBSpline2", first_id + k))
            if rational:
                f.write('  <Basis type="TensorNurbsBasis2">\n')
            f.write('  <Basis type="TensorBSplineBasis2">\n')
            for index, d in enumerate((p.p, p.q)):
                knots = " ".join(["0"] * (d + 1) + ["1"] * (d + 1))
                f.write('   <Basis type="BSplineBasis" index="%d">\n    <KnotVector degree="%d">%s</KnotVector>\n'
                        '   </Basis>\n' % (index, d, knots))
            f.write("  </Basis>\n")
            if rational:
                f.write("  <weights>%s</weights>\n  </Basis>\n" % " ".join(
                    number(p.w[j, i]) for j in range(p.q + 1) for i in range(p.p + 1)))
            f.write('  <coefs geoDim="2">\n')
            for j in range(p.q + 1):
                for i in range(p.p + 1):
                    f.write("%s %s\n" % (number(p.cp[j, i, 0]), number(p.cp[j, i, 1])))
            f.write("  </coefs>\n </Geometry>\n")
        f.write(' <MultiPatch parDim="2" id="%d">\n  <patches type="id_range">%d %d</patches>\n'
                % (multipatch_id, first_id, first_id + len(patches) - 1))
        f.write("  <interfaces>\n")
        for a, sa, b, sb, rev in interfaces:
            ta, tb = (1 if sa <= 2 else 0), (1 if sb <= 2 else 0)
            dirmap, orient = [0, 0], [1, 1]
            dirmap[ta], dirmap[1 - ta] = tb, 1 - tb
            orient[ta] = 0 if rev else 1
            f.write("   %d %d %d %d %d %d %d %d\n" % (first_id + a, sa, first_id + b, sb, dirmap[0], dirmap[1], orient[0],
                                                     orient[1]))
        f.write("  </interfaces>\n")
        for name, sides in boundary.items():
            f.write('  <boundary name="%s">\n' % name)
            for a, s in sides:
                f.write("   %d %d\n" % (first_id + a, s))
            f.write("  </boundary>\n")
        f.write(" </MultiPatch>\n%s</xml>\n" % (problem or ""))


def lshape_problem(patches, boundary):
    """The Poisson problem of cases/multipatch_lshape.toml as a G+Smo problem file:
    u = sin(2x) cosh(y) + x y, so -div grad u = 3 sin(2x) cosh(y); Dirichlet on the boundary
    named "outer"; Neumann on the two re-entrant sides, one given the flux vector grad u (two
    components) and the other the flux du/dn (one), to exercise both of G+Smo's forms."""
    (pa, sa), (pb, sb) = boundary["reentrant"]
    # Side b's outward normal: the re-entrant sides lie on x = 0 (normal +x) and y = 0 (normal -y).
    x, y = patches[pb].point(*SIDES[sb](0.5))
    flux_b = "2*cos(2*x)*cosh(y) + y" if abs(x) < 1e-12 else "-(sin(2*x)*sinh(y) + x)"
    return """ <Function type="FunctionExpr" id="1" dim="2">3*sin(2*x)*cosh(y)</Function>
 <boundaryConditions id="2" multipatch="0">
  <Function type="FunctionExpr" dim="2" index="0">sin(2*x)*cosh(y) + x*y</Function>
  <Function type="FunctionExpr" dim="2" index="1" c="2">
   <c index="0">2*cos(2*x)*cosh(y) + y</c>
   <c index="1">sin(2*x)*sinh(y) + x</c>
  </Function>
  <Function type="FunctionExpr" dim="2" index="2">%s</Function>
  <bc type="Dirichlet" function="0" unknown="0" name="outer"/>
  <bc type="Neumann" function="1" unknown="0">%d %d</bc>
  <bc type="Neumann" function="2" unknown="0">%d %d</bc>
 </boundaryConditions>
 <Function type="FunctionExpr" id="3" dim="2">sin(2*x)*cosh(y) + x*y</Function>
 <OptionList id="4">
  <real label="quA" desc="Number of quadrature points: quA*deg + quB" value="1"/>
  <int label="quB" desc="Number of quadrature points: quA*deg + quB" value="1"/>
  <int label="quRule" desc="Quadrature rule [1:GaussLegendre,2:GaussLobatto]" value="1"/>
 </OptionList>
""" % (flux_b, pa, sa, pb, sb)


def square(x0, y0, x1, y1):
    return Patch([[[x0, y0], [x1, y0]], [[x0, y1], [x1, y1]]])


def lshape():
    """(-1,1)^2 minus [0,1]x[-1,0]: three unit squares; the middle one turned by a quarter turn
    of its parameter square, so that its interfaces are not the identity."""
    patches = [square(-1, -1, 0, 0), square(-1, 0, 0, 1).turned(1), square(0, 0, 1, 1)]
    label = lambda x: "reentrant" if (abs(x[0]) < 1e-12 and x[1] < 0) or (abs(x[1]) < 1e-12 and x[0] > 0) else "outer"
    return "L-shape (-1,1)^2 minus [0,1]x[-1,0], three patches", patches, label


def arc_patch(r0, r1, a0, a1):
    """The annular sector r0 <= r <= r1, a0 <= angle <= a1 (a1 - a0 <= pi/2): u along the radius
    (linear), v along the angle (a rational quadratic arc); positively oriented."""
    h = (a1 - a0) / 2
    m = a0 + h
    # cos(pi/2) is 6e-17 in floating point: the axes' points are written as exact zeros.
    cos = lambda a: 0.0 if abs(math.cos(a)) < 1e-15 else math.cos(a)
    sin = lambda a: 0.0 if abs(math.sin(a)) < 1e-15 else math.sin(a)
    rows, weights = [], []
    for r in (r0, r1):
        rows.append([[r * cos(a0), r * sin(a0)], [r / math.cos(h) * cos(m), r / math.cos(h) * sin(m)], [r * cos(a1), r * sin(a1)]])
        weights.append([1, math.cos(h), 1])
    return Patch(rows, weights).transposed()


def ring():
    """The annulus 1 <= r <= 2 as four quarter sectors; the second turned by a half turn of its
    parameter square and the fourth by a quarter turn, so interfaces run both ways."""
    q = [arc_patch(1, 2, k * math.pi / 2, (k + 1) * math.pi / 2) for k in range(4)]
    patches = [q[0], q[1].turned(2), q[2], q[3].turned(1)]
    label = lambda x: "inner" if abs(np.hypot(*x) - 1) < 1e-9 else "outer"
    return "annulus 1 <= r <= 2, four patches", patches, label


def quarter_ring():
    """GeoPDEs' ring (one patch): the quarter annulus 1 <= r <= 2 in the first quadrant, as
    knotwork builds it in (cases/geometries.cpp, quarter_annulus_patch): u along the radius, v
    along the angle. Its sides are labelled by where they lie."""
    patches = [arc_patch(1, 2, 0, math.pi / 2)]

    def label(x):
        r = np.hypot(*x)
        return "inner" if abs(r - 1) < 1e-9 else "outer" if abs(r - 2) < 1e-9 else "x_axis" if abs(x[1]) < 1e-9 else "y_axis"

    return "quarter annulus 1 <= r <= 2 (GeoPDEs' ring), one patch", patches, label


def plate_with_hole():
    """The quarter of the square plate [0,4]^2 outside the disc of radius 1 (the elasticity
    benchmark's domain): two NURBS patches, each between an eighth of the circle and a side of
    the square, joined along the diagonal."""
    def eighth(a0, a1, outer):
        h = (a1 - a0) / 2
        m = a0 + h
        arc = [[math.cos(a0), math.sin(a0)], [math.cos(m) / math.cos(h), math.sin(m) / math.cos(h)],
               [math.cos(a1), math.sin(a1)]]
        return Patch([arc, outer], [[1, math.cos(h), 1], [1, math.cos(h), 1]]).transposed()
    a = eighth(0, math.pi / 4, [[4, 0], [4, 2], [4, 4]])
    b = eighth(math.pi / 4, math.pi / 2, [[4, 4], [2, 4], [0, 4]])

    def label(x):
        if abs(np.hypot(*x) - 1) < 1e-9:
            return "hole"
        if abs(x[0]) < 1e-12 or abs(x[1]) < 1e-12:
            return "symmetry"
        return "outer"
    return "plate with a hole: [0,4]^2 outside the unit disc, two NURBS patches", [a, b], label


def plus_domain():
    """A plus-shaped domain of 12 curved patches: the 4 x 4 grid of unit squares on [0,4]^2
    without its corner squares, mapped by F(x, y) = (x + y^2/16, y - x^2/20). F is quadratic,
    so each image is exactly a biquadratic Bezier patch (its control points solve the 3 x 3
    interpolation at the parameters 0, 1/2, 1); shared edges are images of the same segments,
    so the patches meet exactly. Every third patch is turned by a quarter turn of its parameter
    square, every fourth by a half turn."""
    F = lambda x, y: (x + y * y / 16, y - x * x / 20)
    t = np.array([0.0, 0.5, 1.0])
    B = np.array([[binom(2, a) * s**a * (1 - s) ** (2 - a) for a in range(3)] for s in t])
    Binv = np.linalg.inv(B)
    patches = []
    for j in range(4):
        for i in range(4):
            if (i in (0, 3)) and (j in (0, 3)):
                continue
            values = np.array([[F(i + u, j + v) for u in t] for v in t])  # [v][u]
            cp = np.einsum("ab,bcx,dc->adx", Binv, values, Binv)
            p = Patch(cp)
            k = len(patches)
            if k % 3 == 2:
                p = p.turned(1)
            if k % 4 == 3:
                p = p.turned(2)
            patches.append(p)
    label = lambda x: "left" if x[0] < 1.2 and x[1] > 0.8 and x[1] < 3.2 and x[0] < 0.3 + x[1] ** 2 / 16 else "rest"
    return "a plus-shaped domain of 12 curved biquadratic patches", patches, label


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", nargs="?", default=os.path.join(os.path.dirname(__file__), "..", "cases", "geometries"),
                        help="the folder to write into (default: cases/geometries)")
    out = parser.parse_args().out
    os.makedirs(out, exist_ok=True)
    for name, build in (("lshape_3patches", lshape), ("ring_4patches", ring), ("plate_with_hole", plate_with_hole),
                        ("plus_12patches", plus_domain), ("quarter_ring", quarter_ring)):
        title, patches, label = build()
        interfaces, boundary = topology(patches, label)
        write_geopdes(os.path.join(out, name + ".txt"), title, patches, interfaces, boundary)
        write_gismo(os.path.join(out, name + ".xml"), title, patches, interfaces, boundary)
        if name == "lshape_3patches":
            problem = os.path.join(out, "..", "multipatch_lshape_problem.xml")
            write_gismo(problem, title + ", with the Poisson problem of cases/multipatch_lshape.toml", patches,
                        interfaces, boundary, lshape_problem(patches, boundary))
        print("%s: %d patches, %d interfaces, boundaries %s" % (
            name, len(patches), len(interfaces), {k: len(v) for k, v in boundary.items()}))


if __name__ == "__main__":
    main()
