// T-mesh helpers shared by the tests of the spline constructions over T-meshes.
#pragma once
#include <gmpxx.h>

#include <functional>
#include <random>
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork::testing {

// The rational a/b in canonical form (mpq_class(a, b) alone is not canonicalized).
inline mpq_class q(long a, long b = 1) {
  mpq_class r(a, b);
  r.canonicalize();
  return r;
}

// Random hierarchical-style T-meshes: random cells split in halves, in x or y.
// Starts from `cells` (default the unit square), so lines of the start stay cross-cuts.
inline std::vector<RationalBox> random_halvings(std::mt19937& rng, int splits,
                                                std::vector<RationalBox> cells = {{0, 0, 1, 1}}) {
  for (int s = 0; s < splits; ++s) {
    const size_t i = std::uniform_int_distribution<size_t>(0, cells.size() - 1)(rng);
    RationalBox a = cells[i], b = a;
    if (rng() % 2) a.x1 = b.x0 = (a.x0 + a.x1) / 2;
    else a.y1 = b.y0 = (a.y0 + a.y1) / 2;
    cells[i] = a;
    cells.push_back(b);
  }
  return cells;
}

// The pinwheel of cases/tmeshes/pinwheel_special.toml with the first ray's foot at x = p
// (dim S(2, 2, 1, 1) = 30 at p = 5/2, 29 elsewhere: test_tmesh_conformality).
inline std::vector<AxisSegment> pinwheel_segments(const mpq_class& p) {
  return {{false, 2, 2, 5},      {true, 4, 2, 5},       {false, 4, 1, 4},      {true, 2, 1, 4},
          {true, p, 0, 2},       {false, q(5, 2), 4, 6}, {true, q(7, 2), 4, 6}, {false, q(7, 2), 0, 2}};
}
inline std::vector<RationalBox> pinwheel_with_ray_at(const mpq_class& p) {
  return insert_segments(grid_cells({0, 1, 5, 6}, {0, 1, 5, 6}), pinwheel_segments(p));
}

// 5/2 + (2^61 - 1) / 2^71: not 5/2, but 5/2 modulo the prime 2^61 - 1, the first prime of
// the modular ranks. The pinwheel with its ray there has dimension 29 over Q and 30 modulo
// that prime: the two primes disagree.
inline mpq_class unlucky_ray_foot() {
  mpq_class p = q(5, 2) + mpq_class(mpz_class((mpz_class(1) << 61) - 1), mpz_class(1) << 71);
  p.canonicalize();
  return p;
}

// Whether the function `value(x, y)` (exact) is one polynomial of bidegree (m, n) on every
// cell: on lines across each cell, 3 (order + 1) equispaced values must have zero
// differences of order m + 1 in x (n + 1 in y) in every window, so that a break anywhere but
// very near a cell's ends is seen.
inline bool polynomial_per_cell(const RectangularPartition& mesh, int m, int n,
                                const std::function<mpq_class(const mpq_class&, const mpq_class&)>& value) {
  for (const auto& c : mesh.cells())
    for (int dir = 0; dir < 2; ++dir) {
      const int order = dir == 0 ? m + 1 : n + 1, other = dir == 0 ? n + 1 : m + 1;
      const int K = 3 * (order + 1);
      for (int line = 0; line <= other; ++line) {
        std::vector<mpq_class> v;
        for (int i = 0; i < K; ++i) {
          const mpq_class s(i + 1, K + 1), t(line + 1, other + 2);
          const mpq_class x = c.x0 + (dir == 0 ? s : t) * (c.x1 - c.x0), y = c.y0 + (dir == 0 ? t : s) * (c.y1 - c.y0);
          v.push_back(value(x, y));
        }
        for (int k = 0; k < order; ++k)
          for (int i = 0; i + 1 < K - k; ++i) v[i] = v[i + 1] - v[i];
        for (int i = 0; i < K - order; ++i)
          if (v[i] != 0) return false;
      }
    }
  return true;
}

}  // namespace knotwork::testing
