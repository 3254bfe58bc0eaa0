// PT-splines on a T-mesh: the certified minimal extension or a full one (horizontal or
// vertical cross-cuts), Extended Edge Elimination on it, and the choice between them. The
// Bernstein form, the changes of basis and the checks by evaluation are in
// pt_cell_polynomials.cpp, pt_change_of_basis.cpp and pt_evaluation.cpp.
#include "basis/pt/pt_spline.hpp"

#include <algorithm>
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <tuple>
#include <mutex>
#include <unordered_map>

#include "basis/tmesh/lr_spline.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/pt/pt_eee.hpp"
#include "basis/exact/sparse_rank.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"

namespace knotwork {

using namespace pt_detail;

namespace {

// The partition with x and y exchanged.
RectangularPartition transposed(const RectangularPartition& mesh) {
  std::vector<RationalBox> cells;
  for (const auto& c : mesh.cells()) cells.push_back({c.y0, c.x0, c.y1, c.x1});
  return RectangularPartition(std::move(cells));
}

// Pairs (cell, grid line strictly inside it) for horizontal lines.
long horizontal_extended_edges(const RectangularPartition& mesh, const Grid& g) {
  long count = 0;
  for (const auto& c : mesh.cells()) count += g.index_y(c.y1) - g.index_y(c.y0) - 1;
  return count;
}


// The construction with horizontal lines extended, on `mesh` as given.
PtSplineBasis build_horizontal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0) {
  const Grid g = make_grid(mesh);
  PtSplineBasis B;
  B.m = m, B.n = n, B.extension = PtExtension::kHorizontal, B.c0 = c0;
  // Global y knots: every y-coordinate, simple, except the C^0 lines (multiplicity n).
  std::vector<mpq_class> interior_y;
  for (int iy = 1; iy < g.ny(); ++iy) interior_y.insert(interior_y.end(), contains(c0.y, g.Y[iy]) ? n : 1, g.Y[iy]);
  const std::vector<mpq_class> KY = open_knot_vector(interior_y, g.Y.front(), g.Y.back(), n);
  const int ny = static_cast<int>(KY.size()) - n - 1;
  std::vector<std::vector<int>> columns_of_row_spline(ny);  // spline indices per j
  for (int j = 0; j < ny; ++j) {
    const std::vector<mpq_class> ky(KY.begin() + j, KY.begin() + j + n + 2);
    const int s0 = g.index_y(ky.front()), s1 = g.index_y(ky.back());
    // Vertical lines of T across every strip of supp N_j.
    std::vector<mpq_class> interior_x;
    for (int ix = 1; ix < g.nx(); ++ix) {
      bool across = true;
      for (int s = s0; s < s1 && across; ++s) across = g.at(ix - 1, s) != g.at(ix, s);
      if (across) interior_x.insert(interior_x.end(), contains(c0.x, g.X[ix]) ? m : 1, g.X[ix]);
    }
    const std::vector<mpq_class> KX = open_knot_vector(interior_x, g.X.front(), g.X.back(), m);
    for (size_t i = 0; i + m + 1 < KX.size(); ++i) {
      columns_of_row_spline[j].push_back(static_cast<int>(B.splines.size()));
      B.splines.push_back({std::vector<mpq_class>(KX.begin() + i, KX.begin() + i + m + 2), ky});
    }
  }

  // EEE rows: for each cell of T and each grid line y = Y_k strictly inside it, the jump of
  // d^n/dy^n across Y_k, a polynomial of degree m in x on [x0, x1] (no knot of any M_{j,i}
  // lies inside a cell its support meets), vanishes at m + 1 points.
  std::vector<EeeRow> rows;
  for (const auto& c : mesh.cells()) {
    for (int k = g.index_y(c.y0) + 1; k < g.index_y(c.y1); ++k) {
      ++B.extended_edges;
      const mpq_class& yk = g.Y[k];
      std::vector<std::pair<int, mpq_class>> jumps;  // (j, jump of N_j^(n) at yk)
      for (int j = 0; j < ny; ++j) {
        if (KY[j] > yk || KY[j + n + 1] < yk) continue;  // an end knot jumps too
        const std::vector<mpq_class> ky(KY.begin() + j, KY.begin() + j + n + 2);
        mpq_class jump = top_derivative_jump(ky, yk);
        if (jump != 0) jumps.emplace_back(j, std::move(jump));
      }
      for (int q = 0; q <= m; ++q) {
        const mpq_class xq = c.x0 + (c.x1 - c.x0) * (q + 1) / (m + 2);
        std::vector<std::pair<int, mpq_class>> row;
        for (const auto& [j, jump] : jumps)
          for (int col : columns_of_row_spline[j]) {
            const auto& kx = B.splines[col].x;
            if (kx.front() >= xq || kx.back() <= xq) continue;
            mpq_class v = jump * bspline_value<mpq_class>(kx, xq);
            if (v != 0) row.emplace_back(col, std::move(v));
          }
        if (!row.empty()) rows.push_back(std::move(row));
      }
    }
  }
  eliminate_extended_edges(B, rows, g, mesh);
  return B;
}

}  // namespace

std::optional<PtExtension> parse_pt_extension(const std::string& name) {
  for (PtExtension e : {PtExtension::kAuto, PtExtension::kMinimal, PtExtension::kHorizontal, PtExtension::kVertical,
                        PtExtension::kDiagonalizable})
    if (name == pt_extension_name(e)) return e;
  return std::nullopt;
}

const char* pt_extension_name(PtExtension extension) {
  switch (extension) {
    case PtExtension::kAuto: return "auto";
    case PtExtension::kMinimal: return "minimal";
    case PtExtension::kHorizontal: return "horizontal";
    case PtExtension::kVertical: return "vertical";
    case PtExtension::kDiagonalizable: return "diagonalizable";
  }
  return "?";
}

namespace {

// Makes `B` a certified basis of S(T), or says why it cannot be one. Its functions lie in S(T)
// by construction. Their exact cell polynomials are eliminated modulo a prime, smallest
// support first, and each function that depends on the ones before it is dropped: the LR
// B-splines of T^e can be dependent and still span S(T^e) (on Dokken-Lyche-Pettersen's mesh
// they do, with T^e = T). The independent rest must be as many as the brute-force
// dimension. The ranks are modular (over Q when the two primes disagree), so a certificate
// is never wrong: dim <= unknowns - rank mod p (rank mod p <= rank over Q), and rows
// independent mod p are independent over Q.
std::string certify(PtSplineBasis& B, const RectangularPartition& mesh, long dimension) {
  // An insertion order that fell short stopped before listing its null vectors.
  const long count =
      B.short_of_dimension > 0 ? dimension - B.short_of_dimension : static_cast<long>(B.functions.size());
  if (count < dimension) return std::to_string(count) + " functions for a space of dimension " + std::to_string(dimension);
  // The functions are the untouched B-splines and, per EEE block, null vectors kept only when
  // exactly independent of the block's earlier ones: their coefficient matrix has full row
  // rank. With the B-splines independent (peeling) the functions are too, and being as many
  // as the dimension they are a basis. No cell polynomial is needed: on a 8228-cell degree-3
  // mesh those took 7.5 of the 10 s of the construction.
  if (B.splines_independent && count == dimension) return {};
  const long per_cell = static_cast<long>(B.m + 1) * (B.n + 1);
  const auto polynomials = pt_cell_polynomials_exact(B, mesh);
  std::vector<long> order(count);
  std::iota(order.begin(), order.end(), 0L);
  std::stable_sort(order.begin(), order.end(),
                   [&](long a, long b) { return polynomials[a].size() < polynomials[b].size(); });
  std::vector<SparseRationalRow> rows;
  for (long f : order) {
    SparseRationalRow r;
    for (const auto& [k, coefficients] : polynomials[f])
      for (long a = 0; a < per_cell; ++a)
        if (coefficients[a] != 0) r.terms.emplace_back(k * per_cell + a, coefficients[a]);
    rows.push_back(std::move(r));
  }
  std::vector<bool> independent;
  const long rank = rank_reliable(rows, per_cell * mesh.num_cells(), &independent);
  if (rank != dimension)
    return "the " + std::to_string(count) + " functions have rank " + std::to_string(rank) +
           " for a space of dimension " + std::to_string(dimension);
  if (rank == count) return {};
  std::vector<bool> keep(count);
  for (long i = 0; i < count; ++i) keep[order[i]] = independent[i];
  std::vector<std::vector<std::pair<int, mpq_class>>> kept;
  int untouched = 0;
  for (long f = 0; f < count; ++f) {
    if (!keep[f]) continue;
    untouched += f < B.untouched;
    kept.push_back(std::move(B.functions[f]));
  }
  B.functions = std::move(kept);
  B.untouched = untouched;
  B.dropped_dependent = static_cast<int>(count - rank);
  return {};
}

// dim S(m, n, m-1, n-1) of T, C^0 across `c0`: the smoothing-cofactor count (one unknown per
// interior vertex, n + 1 or m + 1 conditions per T l-edge), an upper bound that is exact
// unless both primes divide a minor. It replaced the brute force on cell polynomials (16
// unknowns per bicubic cell), which took 4.5 of the 11 s of a 4817-cell degree-3 build; the
// two are compared on every shipped and many random T-meshes in test_tmesh_conformality.
long dimension_of(const RectangularPartition& mesh, int m, int n, const C0Lines& c0) {
  return conformality_count(partition_topology(mesh), m, n, c0, RankMethod::kModular).dimension;
}

// One attempt at the minimal extension: the certified basis, or why there is none. With
// `diagonalizable`, a T^e that fails the ordering test is refused too.
std::optional<PtSplineBasis> attempt_minimal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0,
                                             const MinimalVariant& variant, long dimension, bool diagonalizable,
                                             std::string& why) {
  try {
    std::optional<PtSplineBasis> B = build_minimal(mesh, m, n, c0, variant, dimension);
    if (!B) {
      why = "an l-edge could not be inserted even as a full line";
      return std::nullopt;
    }
    if (diagonalizable &&
        !diagonalizable_by_ordering(partition_topology(RectangularPartition(B->extension_cells)), m, n)) {
      why = "no lengthening made T^e diagonalizable";
      return std::nullopt;
    }
    why = certify(*B, mesh, dimension);
    if (why.empty()) return B;
  } catch (const std::logic_error& e) {  // a block's modular rank fell below its rank over Q
    why = e.what();
  }
  return std::nullopt;
}

// T^e of a full extension: every cell of T cut at every y (horizontal) or x coordinate of T.
std::vector<RationalBox> full_extension_cells(const RectangularPartition& mesh, bool horizontal) {
  std::set<mpq_class> lines;
  for (const auto& c : mesh.cells()) lines.insert(horizontal ? c.y0 : c.x0);
  std::vector<RationalBox> cells;
  for (const auto& c : mesh.cells()) {
    const mpq_class start = horizontal ? c.y0 : c.x0, end = horizontal ? c.y1 : c.x1;
    std::vector<mpq_class> cuts{start};
    for (auto it = lines.upper_bound(start); it != lines.end() && *it < end; ++it) cuts.push_back(*it);
    cuts.push_back(end);
    for (size_t i = 0; i + 1 < cuts.size(); ++i)
      cells.push_back(horizontal ? RationalBox{c.x0, cuts[i], c.x1, cuts[i + 1]}
                                 : RationalBox{cuts[i], c.y0, cuts[i + 1], c.y1});
  }
  return cells;
}

}  // namespace

PtSplineBasis pt_spline_basis(const RectangularPartition& mesh, int m, int n, PtExtension extension, const C0Lines& c0) {
  if (m < 1 || n < 1) throw std::invalid_argument("PT-splines need degrees m, n >= 1");
  {
    const Grid g = make_grid(mesh);
    for (int dir = 0; dir < 2; ++dir)
      for (const mpq_class& v : dir == 0 ? c0.x : c0.y) {
        const auto& L = dir == 0 ? g.X : g.Y;
        const int i = dir == 0 ? g.index_x(v) : g.index_y(v);
        bool cut = i > 0 && i + 1 < static_cast<int>(L.size()) && L[i] == v;
        for (int s = 0; s < (dir == 0 ? g.ny() : g.nx()) && cut; ++s)
          cut = dir == 0 ? g.at(i - 1, s) != g.at(i, s) : g.at(s, i - 1) != g.at(s, i);
        if (!cut)
          throw std::invalid_argument(std::string("the C0 line ") + (dir == 0 ? "x = " : "y = ") + v.get_str() +
                                      " is not a line of the T-mesh from boundary to boundary");
      }
  }
  std::string refused;
  if (extension == PtExtension::kDiagonalizable) {
    const long dimension = dimension_of(mesh, m, n, c0);
    const Grid g = make_grid(mesh);
    std::string why;
    for (int k = 0; k <= std::max(g.nx(), g.ny()); ++k)
      for (bool shortest : {false, true})
        if (auto B = attempt_minimal(mesh, m, n, c0, MinimalVariant{shortest, k}, dimension, true, why)) {
          B->extension = PtExtension::kDiagonalizable;
          return std::move(*B);
        }
    throw std::runtime_error("diagonalizable PT-spline extension: " + why);
  }
  if (extension == PtExtension::kAuto || extension == PtExtension::kMinimal) {
    const long dimension = dimension_of(mesh, m, n, c0);
    for (const MinimalVariant variant : {MinimalVariant{false, 0}, MinimalVariant{true, 0}, MinimalVariant{false, 1},
                                         MinimalVariant{true, 1}}) {
      std::string why;
      if (auto B = attempt_minimal(mesh, m, n, c0, variant, dimension, false, why)) return std::move(*B);
      if (refused.empty()) refused = why + " (and in the three other insertion orders)";  // the first reason
    }
    if (extension == PtExtension::kMinimal) throw std::runtime_error("minimal PT-spline extension: " + refused);
  }
  const RectangularPartition flipped = transposed(mesh);
  if (extension == PtExtension::kAuto) {
    const long h = horizontal_extended_edges(mesh, make_grid(mesh));
    const long v = horizontal_extended_edges(flipped, make_grid(flipped));
    extension = v < h ? PtExtension::kVertical : PtExtension::kHorizontal;
  }
  if (extension == PtExtension::kHorizontal) {
    PtSplineBasis B = build_horizontal(mesh, m, n, c0);
    B.minimal_refused = refused;
    B.extension_cells = full_extension_cells(mesh, true);
    return B;
  }
  PtSplineBasis B = build_horizontal(flipped, n, m, C0Lines{c0.y, c0.x});
  for (auto& s : B.splines) std::swap(s.x, s.y);
  std::swap(B.m, B.n);
  B.c0 = c0;
  B.extension = PtExtension::kVertical;
  B.minimal_refused = refused;
  B.extension_cells = full_extension_cells(mesh, false);
  return B;
}

}  // namespace knotwork
