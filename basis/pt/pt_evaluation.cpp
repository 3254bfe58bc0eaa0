// Checks of PT-splines by direct evaluation: a function's exact value at a point, and the
// largest jump of derivatives up to order m-1 / n-1 across the T-mesh's interior edges.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/lr_spline.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/pt/pt_eee.hpp"
#include "basis/pt/pt_spline.hpp"

namespace knotwork {

using namespace pt_detail;

mpq_class pt_evaluate(const PtSplineBasis& B, int f, const mpq_class& x, const mpq_class& y) {
  mpq_class v = 0;
  for (const auto& [s, c] : B.functions[f]) {
    const auto& sp = B.splines[s];
    if (x < sp.x.front() || x >= sp.x.back() || y < sp.y.front() || y >= sp.y.back()) continue;
    v += c * bspline_value<mpq_class>(sp.x, x) * bspline_value<mpq_class>(sp.y, y);
  }
  return v;
}

namespace {

// d^k/ds^k of the Bernstein polynomial with coefficients b (degree p) at s, on [0, 1].
double bernstein_derivative(std::vector<double> b, int k, double s) {
  int p = static_cast<int>(b.size()) - 1;
  for (int d = 0; d < k; ++d, --p) {
    for (int i = 0; i < p; ++i) b[i] = p * (b[i + 1] - b[i]);
    b.pop_back();
  }
  if (b.empty()) return 0;
  for (int level = static_cast<int>(b.size()) - 1; level > 0; --level)
    for (int i = 0; i < level; ++i) b[i] = (1 - s) * b[i] + s * b[i + 1];
  return b[0];
}

}  // namespace

double pt_smoothness_residual(const PtCellPolynomials& polys, const RectangularPartition& mesh, int m, int n,
                              const C0Lines& c0) {
  const auto& edges = mesh.shared_edges();
  std::vector<std::vector<int>> edges_of_cell(mesh.num_cells());
  for (size_t e = 0; e < edges.size(); ++e) {
    edges_of_cell[edges[e].first].push_back(static_cast<int>(e));
    edges_of_cell[edges[e].second].push_back(static_cast<int>(e));
  }
  const std::vector<double> zero((m + 1) * (n + 1), 0.0);
  double worst = 0;
  for (const auto& f : polys) {
    std::map<int, const std::vector<double>*> on;
    std::set<int> near;  // edges of the cells where f lives
    double scale = 0;
    for (const auto& [k, c] : f) {
      on[k] = &c;
      near.insert(edges_of_cell[k].begin(), edges_of_cell[k].end());
      for (double v : c) scale = std::max(scale, std::abs(v));
    }
    if (scale == 0) continue;
    for (int index : near) {
      const auto& e = edges[index];
      const int pn = e.vertical ? m : n, pt = e.vertical ? n : m;  // degree across / along
      const int orders = contains(e.vertical ? c0.x : c0.y, e.position) ? 1 : pn;  // derivatives kept
      const int points = m + n + 2;
      double h[2];
      const std::vector<double>* b[2];
      for (int side = 0; side < 2; ++side) {
        const int cell = side == 0 ? e.first : e.second;
        const auto& box = mesh.cells()[cell];
        h[side] = mpq_class(e.vertical ? box.x1 - box.x0 : box.y1 - box.y0).get_d();
        const auto it = on.find(cell);
        b[side] = it == on.end() ? &zero : it->second;
      }
      for (int q = 0; q < points; ++q) {
        const mpq_class t = e.from + (e.to - e.from) * (q + 1) / (points + 1);
        // Each cell polynomial restricted to the line through the point across the edge: a
        // univariate Bernstein polynomial in the normal direction.
        std::vector<double> normal[2];
        for (int side = 0; side < 2; ++side) {
          const auto& box = mesh.cells()[side == 0 ? e.first : e.second];
          const double along = e.vertical ? mpq_class((t - box.y0) / (box.y1 - box.y0)).get_d()
                                          : mpq_class((t - box.x0) / (box.x1 - box.x0)).get_d();
          normal[side].resize(pn + 1);
          std::vector<double> line(pt + 1);
          for (int i = 0; i <= pn; ++i) {
            for (int j = 0; j <= pt; ++j) line[j] = e.vertical ? (*b[side])[i + (m + 1) * j] : (*b[side])[j + (m + 1) * i];
            normal[side][i] = bernstein_derivative(line, 0, along);
          }
        }
        // Derivatives 0 .. pn-1 must match; each jump relative to the scale of a k-th
        // derivative on the smaller of the two cells.
        const double h_min = std::min(h[0], h[1]);
        for (int k = 0; k < orders; ++k) {
          const double left = bernstein_derivative(normal[0], k, 1.0) / std::pow(h[0], k);
          const double right = bernstein_derivative(normal[1], k, 0.0) / std::pow(h[1], k);
          worst = std::max(worst, std::abs(left - right) * std::pow(h_min, k) / scale);
        }
      }
    }
  }
  return worst;
}

}  // namespace knotwork
