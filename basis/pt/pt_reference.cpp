#include "basis/pt/pt_reference.hpp"

#include "basis/core/bspline_kernel.hpp"
#include "basis/exact/sparse_rank.hpp"

#include <algorithm>
#include <iterator>
#include <set>
#include <stdexcept>


namespace knotwork {

namespace {

std::vector<mpq_class> open_knots(const std::set<mpq_class>& breaks, int p) {
  return open_knot_vector({std::next(breaks.begin()), std::prev(breaks.end())}, *breaks.begin(), *breaks.rbegin(), p);
}

// Values of all B-splines of degree p at x (x not a knot, or the domain's right end).
std::vector<mpq_class> values(const std::vector<mpq_class>& t, int p, const mpq_class& x) {
  return bspline_kernel::all_at<mpq_class>(t, p, x);
}

// The p-th derivative of B-spline a (degree p) as a combination of the degree-0 B-splines
// (span indicators): p times d/dx N_{i,q} = q/(t_{i+q}-t_i) N_{i,q-1} - q/(t_{i+q+1}-t_{i+1}) N_{i+1,q-1}.
std::vector<mpq_class> top_derivative(const std::vector<mpq_class>& t, int p, int a) {
  std::vector<mpq_class> c(t.size(), mpq_class(0));
  c[a] = 1;
  for (int q = p; q >= 1; --q) {
    std::vector<mpq_class> next(t.size(), mpq_class(0));
    for (size_t i = 0; i + q + 1 < t.size(); ++i) {
      if (c[i] == 0) continue;
      if (t[i + q] != t[i]) next[i] += c[i] * q / (t[i + q] - t[i]);
      if (t[i + q + 1] != t[i + 1]) next[i + 1] -= c[i] * q / (t[i + q + 1] - t[i + 1]);
    }
    c = std::move(next);
  }
  return c;
}

}  // namespace

TensorCombinationBasis pt_full_extension_basis(const RectangularPartition& mesh, int m, int n) {
  if (m < 1 || n < 1) throw std::invalid_argument("pt_full_extension_basis: degrees must be >= 1");
  std::set<mpq_class> xs, ys;
  for (const auto& c : mesh.cells()) {
    xs.insert(c.x0), xs.insert(c.x1);
    ys.insert(c.y0), ys.insert(c.y1);
  }
  TensorCombinationBasis B;
  B.m = m, B.n = n;
  B.knots_x = open_knots(xs, m);
  B.knots_y = open_knots(ys, n);
  B.nx = static_cast<int>(B.knots_x.size()) - m - 1;
  B.ny = static_cast<int>(B.knots_y.size()) - n - 1;
  const int columns = B.nx * B.ny;

  // Jumps of the top derivatives at every interior knot (knot index k: span k-1 | span k).
  auto jumps = [](const std::vector<mpq_class>& t, int p, int count, int k) {
    std::vector<mpq_class> j(count, mpq_class(0));
    for (int a = 0; a < count; ++a) {
      const auto d = top_derivative(t, p, a);
      j[a] = d[k] - d[k - 1];
    }
    return j;
  };
  const std::vector<mpq_class> X(xs.begin(), xs.end()), Y(ys.begin(), ys.end());
  std::vector<std::vector<mpq_class>> rows;
  // An extended segment: grid line x = X[i] across grid interval [Y[j], Y[j+1]] inside a
  // cell of T (not on its boundary). The jump, a spline in y of degree n, is one polynomial
  // there: it vanishes iff it vanishes at n + 1 points of the interval.
  for (int dir = 0; dir < 2; ++dir) {
    const auto& lines = dir == 0 ? X : Y;
    const auto& across = dir == 0 ? Y : X;
    const auto& t_line = dir == 0 ? B.knots_x : B.knots_y;
    const auto& t_along = dir == 0 ? B.knots_y : B.knots_x;
    const int p_line = dir == 0 ? m : n, p_along = dir == 0 ? n : m;
    const int count_line = dir == 0 ? B.nx : B.ny;
    for (size_t i = 1; i + 1 < lines.size(); ++i) {
      const std::vector<mpq_class> jump = jumps(t_line, p_line, count_line, static_cast<int>(i) + p_line);
      for (size_t j = 0; j + 1 < across.size(); ++j) {
        const mpq_class mid_line = lines[i], mid_across = (across[j] + across[j + 1]) / 2;
        bool inside = false;  // the segment's midpoint strictly inside a cell
        for (const auto& c : mesh.cells()) {
          const mpq_class& lo = dir == 0 ? c.x0 : c.y0;
          const mpq_class& hi = dir == 0 ? c.x1 : c.y1;
          const mpq_class& alo = dir == 0 ? c.y0 : c.x0;
          const mpq_class& ahi = dir == 0 ? c.y1 : c.x1;
          if (lo < mid_line && mid_line < hi && alo < mid_across && mid_across < ahi) inside = true;
        }
        if (!inside) continue;
        for (int q = 0; q <= p_along; ++q) {
          const mpq_class s = across[j] + (across[j + 1] - across[j]) * (q + 1) / (p_along + 2);
          const std::vector<mpq_class> along = values(t_along, p_along, s);
          std::vector<mpq_class> row(columns, mpq_class(0));
          bool any = false;
          for (int a = 0; a < count_line; ++a) {
            if (jump[a] == 0) continue;
            for (size_t b = 0; b < along.size(); ++b) {
              if (along[b] == 0) continue;
              const int col = dir == 0 ? a + B.nx * static_cast<int>(b) : static_cast<int>(b) + B.nx * a;
              row[col] = jump[a] * along[b];
              any = true;
            }
          }
          if (any) rows.push_back(std::move(row));
        }
      }
    }
  }
  B.equations = static_cast<long>(rows.size());
  for (auto& v : null_space_exact(std::move(rows), columns, &B.rank)) {
    std::vector<std::pair<int, mpq_class>> f;
    for (int c = 0; c < columns; ++c)
      if (v[c] != 0) f.emplace_back(c, v[c]);
    B.functions.push_back(std::move(f));
  }
  return B;
}

mpq_class evaluate(const TensorCombinationBasis& basis, int function, const mpq_class& x, const mpq_class& y) {
  const auto nx = values(basis.knots_x, basis.m, x), ny = values(basis.knots_y, basis.n, y);
  mpq_class v = 0;
  for (const auto& [c, coefficient] : basis.functions[function]) v += coefficient * nx[c % basis.nx] * ny[c / basis.nx];
  return v;
}

}  // namespace knotwork
