#include "basis/tmesh/spline_dimension.hpp"

#include "basis/exact/sparse_rank.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace knotwork {

namespace {

using Constraint = SparseRationalRow;

long falling(int i, int k) {
  long r = 1;
  for (int t = 0; t < k; ++t) r *= (i - t);
  return r;
}

bool on_line(const std::vector<mpq_class>& lines, const mpq_class& v) {
  return std::find(lines.begin(), lines.end(), v) != lines.end();
}

}  // namespace

std::vector<SparseRationalRow> smoothness_constraints(const RectangularPartition& part, int m, int n, int alpha,
                                                      int beta, const C0Lines& c0) {
  const long per_cell = static_cast<long>(m + 1) * (n + 1);
  auto column = [&](int cell, int i, int j) { return cell * per_cell + i + static_cast<long>(m + 1) * j; };
  std::vector<Constraint> rows;
  for (const auto& e : part.shared_edges()) {
    // Vertical edge x = x0: for each k <= alpha and each power y^j, the coefficient of y^j in
    // d^k/dx^k (p1 - p2)(x0, y) is sum_i falling(i, k) x0^(i-k) (a1_ij - a2_ij).
    int order = e.vertical ? alpha : beta;
    if (on_line(e.vertical ? c0.x : c0.y, e.position)) order = std::min(order, 0);
    const int along = e.vertical ? n : m, across = e.vertical ? m : n;
    for (int k = 0; k <= order; ++k)
      for (int j = 0; j <= along; ++j) {
        Constraint c;
        mpq_class power = 1;  // x0^(i-k)
        for (int i = k; i <= across; ++i) {
          const mpq_class coef = power * falling(i, k);
          if (coef != 0) {
            const int ii = e.vertical ? i : j, jj = e.vertical ? j : i;
            c.terms.emplace_back(column(e.first, ii, jj), coef);
            c.terms.emplace_back(column(e.second, ii, jj), -coef);
          }
          power *= e.position;
        }
        if (!c.terms.empty()) rows.push_back(std::move(c));
      }
  }
  return rows;
}

void check_brute_force_size(long cells, int m, int n, RankMethod method) {
  const long unknowns = cells * (m + 1) * (n + 1);
  const long limit = method == RankMethod::kExact ? kMaxExactBruteForceUnknowns : kMaxBruteForceUnknowns;
  if (unknowns > limit)
    throw std::length_error(std::to_string(cells) + " cells of bi-degree (" + std::to_string(m) + ", " + std::to_string(n) +
                            ") are " + std::to_string(unknowns) + " unknowns, more than the " + std::to_string(limit) +
                            " the brute-force dimension count" + (method == RankMethod::kExact ? " over Q" : "") +
                            " takes (about a minute here)");
}

DimensionResult spline_space_dimension(const RectangularPartition& part, int m, int n, int alpha, int beta,
                                       RankMethod method, const C0Lines& c0) {
  if (m < 0 || n < 0) throw std::invalid_argument("degrees must be >= 0");
  if (alpha < -1 || alpha > m - 1 || beta < -1 || beta > n - 1)
    throw std::invalid_argument("smoothness must be in [-1, degree-1]");
  DimensionResult r;
  r.unknowns = static_cast<long>(part.num_cells()) * (m + 1) * (n + 1);
  const std::vector<Constraint> rows = smoothness_constraints(part, m, n, alpha, beta, c0);
  r.constraints = static_cast<long>(rows.size());
  if (method == RankMethod::kExact) {
    r.rank = rank_exact(rows, r.unknowns);
    r.exact = true;
  } else {
    r.rank = rank_reliable(rows, r.unknowns, nullptr, &r.exact);
  }
  r.dimension = r.unknowns - r.rank;
  return r;
}

}  // namespace knotwork
