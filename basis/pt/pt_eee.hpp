#pragma once
// Internal to basis/: what the PT-spline constructions (pt_spline.cpp, pt_minimal_extension.cpp)
// share: the grid of all coordinates, exact B-spline values and jumps, sparse rational vectors,
// and the Extended Edge Elimination solve itself.
#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "basis/core/bspline_kernel.hpp"
#include "basis/pt/pt_spline.hpp"
#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork::pt_detail {

// Value of the B-spline with local knots t (degree t.size() - 2) at x, not at a knot.
template <class S>
S bspline_value(const std::vector<mpq_class>& knots, const S& x) {
  if constexpr (std::is_same_v<S, mpq_class>) {
    return bspline_kernel::local_value<mpq_class>(knots, x);
  } else {
    std::vector<S> t(knots.size());
    for (size_t i = 0; i < knots.size(); ++i) t[i] = knots[i].get_d();
    return bspline_kernel::local_value<S>(t, x);
  }
}

// The jump of the p-th derivative (p = degree) of the B-spline with local knots t across the
// knot value k: the p-th derivative is piecewise constant on the knot intervals.
mpq_class top_derivative_jump(const std::vector<mpq_class>& t, const mpq_class& k);

// The full grid of all coordinates, and which cell of T covers each grid cell.
struct Grid {
  std::vector<mpq_class> X, Y;
  std::vector<int> owner;  // ix + (X.size() - 1) * iy
  int nx() const { return static_cast<int>(X.size()) - 1; }
  int ny() const { return static_cast<int>(Y.size()) - 1; }
  int at(int ix, int iy) const { return owner[ix + nx() * iy]; }
  int index_x(const mpq_class& v) const { return static_cast<int>(std::lower_bound(X.begin(), X.end(), v) - X.begin()); }
  int index_y(const mpq_class& v) const { return static_cast<int>(std::lower_bound(Y.begin(), Y.end(), v) - Y.begin()); }
  std::vector<std::array<int, 4>> cell_box;  // each cell of T in grid indices: x0, y0, x1, y1
  // The cells of T meeting the grid box [x0, x1) x [y0, y1), in increasing order: a walk from
  // cell to cell (a row of the grid at a time only where some cell ends), not a visit of
  // every grid cell, which costs the square of the number of coordinates on a graded mesh.
  std::vector<int> cells_in(int x0, int y0, int x1, int y1) const;
  // The cells of T meeting the support of a B-spline whose knots are grid coordinates.
  std::vector<int> cells_under(const PtLocalBSpline& s) const {
    return cells_in(index_x(s.x.front()), index_y(s.y.front()), index_x(s.x.back()), index_y(s.y.back()));
  }
};

Grid make_grid(const RectangularPartition& mesh);

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) { return parent[a] == a ? a : parent[a] = find(parent[a]); }
  void join(int a, int b) { parent[find(a)] = find(b); }
};

inline bool contains(const std::vector<mpq_class>& lines, const mpq_class& v) {
  return std::find(lines.begin(), lines.end(), v) != lines.end();
}

using SparseVector = std::map<int, mpq_class>;
void axpy(SparseVector& y, const mpq_class& a, const SparseVector& x);
inline std::vector<std::pair<int, mpq_class>> as_function(const SparseVector& v) { return {v.begin(), v.end()}; }

// Sparse vectors in echelon form (pivot: the leading index). add() reduces `key` by the
// vectors added so far, carrying `companion` along with the same operations, and keeps the
// reduced pair as a new pivot when the key is not zero; returns whether it was not. Pivots are
// never changed, so a sequence of adds is a triangular change of basis.
class SparseEchelon {
 public:
  bool add(SparseVector& key, SparseVector& companion) {
    for (auto it = key.begin(); it != key.end();) {
      const auto p = pivots_.find(it->first);
      if (p == pivots_.end()) {
        ++it;
        continue;
      }
      const int lead = it->first;
      const mpq_class factor = -it->second / p->second.first.at(lead);
      axpy(key, factor, p->second.first);
      axpy(companion, factor, p->second.second);
      it = key.upper_bound(lead);
    }
    if (key.empty()) return false;
    pivots_.emplace(key.begin()->first, std::make_pair(key, companion));
    return true;
  }

 private:
  std::map<int, std::pair<SparseVector, SparseVector>> pivots_;  // leading index -> (key, companion)
};

// One EEE equation: sum over (B-spline index, coefficient) = 0.
using EeeRow = std::vector<std::pair<int, mpq_class>>;

// Solves the EEE equations over B.splines block by block (B-splines linked by a common
// equation) and fills B.functions: the B-splines no equation touches, untouched, then a local
// basis of each block's null space (exact). Also sets equations, rank, blocks, largest_block,
// untouched. Every knot of B.splines must be a coordinate of `mesh` (g = make_grid(mesh)).
// Returns the number of functions. With `needed` >= 0 and fewer functions than that, only
// the untouched B-splines are listed and B.short_of_dimension says how many are missing.
long eliminate_extended_edges(PtSplineBasis& B, const std::vector<EeeRow>& rows, const Grid& g,
                              const RectangularPartition& mesh, long needed = -1);

// The construction on an LR-mesh extension of T (pt_minimal_extension.cpp); nullopt when an
// l-edge cannot be inserted even as a full line. The LR B-splines of the extension need not
// span all of S(T^e): the result can miss functions, and whether it does depends on the
// order of insertion (on 12 adaptive L-shape meshes at degrees 2 and 3, longest-first missed
// a function in 6 of the 24 cases, shortest-first in 3, both in 2), hence the variants,
// tried in turn by pt_spline_basis.
struct MinimalVariant {
  bool shortest_first = false;
  int extra_steps = 0;
};
// `needed`: the dimension of S(T), passed on to eliminate_extended_edges.
std::optional<PtSplineBasis> build_minimal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0,
                                           const MinimalVariant& variant, long needed = -1);

}  // namespace knotwork::pt_detail
