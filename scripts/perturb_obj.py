#!/usr/bin/env python3
"""A quad mesh (.obj) with every interior vertex moved by a pseudo-random amount, written with
17 significant digits: planar data whose exact rationals are long (100+ bits), the worst case
for the exact G1 constructions (docs/records/g1-poisson-results-2026-12-04.md, "Performance"). Boundary vertices (on the
bounding box) stay, so the domain is unchanged. Deterministic for a given seed.

    scripts/perturb_obj.py cases/meshes/mixed_valences.obj 0.003 1 > cases/meshes/mixed_valences_17digit.obj
"""
import argparse
import random
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh", help="the quad mesh (.obj)")
    parser.add_argument("amount", type=float, help="the largest move in x and y")
    parser.add_argument("seed", type=int, help="the pseudo-random seed")
    a = parser.parse_args()
    path, amount, seed = a.mesh, a.amount, a.seed
    lines = open(path).read().splitlines()
    vertices = [[float(t) for t in l.split()[1:4]] for l in lines if l.startswith("v ")]
    if not vertices:
        sys.exit(f"{path}: no vertices")
    lo = [min(v[i] for v in vertices) for i in range(2)]
    hi = [max(v[i] for v in vertices) for i in range(2)]
    rng = random.Random(seed)
    print(f"# {path} with every interior vertex moved by up to {amount} in x and y "
          f"(scripts/perturb_obj.py, seed {seed}), written with %.17g")
    k = 0
    for l in lines:
        if not l.startswith("v "):
            if not l.startswith("#"):
                print(l)
            continue
        x, y, z = vertices[k]
        k += 1
        dx, dy = rng.uniform(-amount, amount), rng.uniform(-amount, amount)
        if lo[0] < x < hi[0] and lo[1] < y < hi[1]:
            x, y = x + dx, y + dy
        print("v %.17g %.17g %.17g" % (x, y, z))


if __name__ == "__main__":
    main()
