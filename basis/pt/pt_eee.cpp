#include "basis/pt/pt_eee.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <tuple>

#include "basis/exact/sparse_rank.hpp"

namespace knotwork::pt_detail {

// The jump of the p-th derivative (p = degree) of the B-spline with local knots t across the
// knot value k: the p-th derivative is piecewise constant on the knot intervals.
mpq_class top_derivative_jump(const std::vector<mpq_class>& t, const mpq_class& k) {
  const int p = static_cast<int>(t.size()) - 2;
  std::vector<mpq_class> c(p + 2, mpq_class(0));  // coefficients on degree-q indicator splines
  c[0] = 1;
  for (int q = p; q >= 1; --q) {
    // B-splines of degree q on knots t[i..i+q+1], i = 0..p-q; their derivatives in degree q-1.
    std::vector<mpq_class> next(p + 2, mpq_class(0));
    for (int i = 0; i + q <= p; ++i) {
      if (c[i] == 0) continue;
      if (t[i + q] != t[i]) next[i] += c[i] * q / (t[i + q] - t[i]);
      if (t[i + q + 1] != t[i + 1]) next[i + 1] -= c[i] * q / (t[i + q + 1] - t[i + 1]);
    }
    c = std::move(next);
  }
  // c[i]: value of the p-th derivative on [t_i, t_{i+1}).
  mpq_class below = 0, above = 0;
  for (int i = 0; i <= p; ++i) {
    if (t[i + 1] == k && t[i] < k) below = c[i];
    if (t[i] == k && k < t[i + 1]) above = c[i];
  }
  return above - below;
}

Grid make_grid(const RectangularPartition& mesh) {
  std::set<mpq_class> xs, ys;
  for (const auto& c : mesh.cells()) {
    xs.insert(c.x0), xs.insert(c.x1);
    ys.insert(c.y0), ys.insert(c.y1);
  }
  Grid g;
  g.X.assign(xs.begin(), xs.end());
  g.Y.assign(ys.begin(), ys.end());
  g.owner.assign(static_cast<size_t>(g.nx()) * g.ny(), -1);
  g.cell_box.resize(mesh.num_cells());
  for (int k = 0; k < mesh.num_cells(); ++k) {
    const auto& c = mesh.cells()[k];
    g.cell_box[k] = {g.index_x(c.x0), g.index_y(c.y0), g.index_x(c.x1), g.index_y(c.y1)};
    for (int iy = g.cell_box[k][1]; iy < g.cell_box[k][3]; ++iy)
      for (int ix = g.cell_box[k][0]; ix < g.cell_box[k][2]; ++ix) g.owner[ix + g.nx() * iy] = k;
  }
  return g;
}

std::vector<int> Grid::cells_in(int x0, int y0, int x1, int y1) const {
  std::vector<int> out;
  for (int iy = y0; iy < y1;) {
    int next = y1;
    for (int ix = x0; ix < x1;) {
      const int k = at(ix, iy);
      out.push_back(k);
      ix = cell_box[k][2];
      next = std::min(next, cell_box[k][3]);
    }
    iy = next;
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void axpy(SparseVector& y, const mpq_class& a, const SparseVector& x) {
  for (const auto& [k, v] : x) {
    mpq_class& t = y[k];
    t += a * v;
    if (t == 0) y.erase(k);
  }
}

namespace {

// Grid box [x0, x1) x [y0, y1) in grid cell indices.
struct GridBox {
  int x0, y0, x1, y1;
  bool operator<(const GridBox& o) const { return std::tie(x0, y0, x1, y1) < std::tie(o.x0, o.y0, o.x1, o.y1); }
  bool contains(const GridBox& o) const { return x0 <= o.x0 && o.x1 <= x1 && y0 <= o.y0 && o.y1 <= y1; }
};

// A basis of the null space of one EEE block made of local vectors: the null vectors of the
// B-splines inside small boxes of T cells (the support of one B-spline snapped to the cells
// of T, then grown by a layer of cells at a time), smallest boxes first, each kept when it is
// independent (exactly) of those kept before. The reduced row echelon basis of the whole
// block is also a basis, but on graded meshes its vectors spread over the block (up to 123
// of 454 cells on an adaptive L-shape mesh, where the local vectors cover at most 62).
std::vector<SparseVector> local_null_basis(const std::vector<int>& cols, const std::vector<int>& block_rows,
                                           const std::vector<std::vector<std::pair<int, mpq_class>>>& rows,
                                           const std::vector<GridBox>& support, const Grid& g, const RectangularPartition& mesh,
                                           long nullity) {
  std::map<int, std::vector<int>> rows_of_col;
  for (int r : block_rows)
    for (const auto& [col, v] : rows[r]) rows_of_col[col].push_back(r);
  auto snap = [&](GridBox b) {  // grow to a union of cells of T
    for (bool grown = true; grown;) {
      grown = false;
      for (int iy = b.y0; iy < b.y1; ++iy)
        for (int ix = b.x0; ix < b.x1; ++ix) {
          const auto& c = mesh.cells()[g.at(ix, iy)];
          const GridBox cb{g.index_x(c.x0), g.index_y(c.y0), g.index_x(c.x1), g.index_y(c.y1)};
          if (!b.contains(cb)) {
            b = {std::min(b.x0, cb.x0), std::min(b.y0, cb.y0), std::max(b.x1, cb.x1), std::max(b.y1, cb.y1)};
            grown = true;
          }
        }
    }
    return b;
  };
  auto area = [&](const GridBox& b) { return mpq_class((g.X[b.x1] - g.X[b.x0]) * (g.Y[b.y1] - g.Y[b.y0])); };
  std::vector<int> order = cols;  // seeds: smallest supports first
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return area(support[a]) < area(support[b]); });
  std::vector<GridBox> boxes;
  for (int s : order) boxes.push_back(snap(support[s]));

  SparseEchelon echelon;
  std::vector<SparseVector> out;
  auto consider = [&](SparseVector f) {
    SparseVector reduced = f, none;
    if (echelon.add(reduced, none)) out.push_back(std::move(f));
  };
  std::set<std::vector<int>> tried_sets;  // different boxes often hold the same B-splines
  auto null_vectors = [&](const GridBox& box) {
    std::vector<SparseVector> found;
    std::vector<int> inside;
    for (int col : cols)
      if (box.contains(support[col])) inside.push_back(col);
    if (inside.empty() || !tried_sets.insert(inside).second) return found;
    std::set<int> local_rows;
    for (int col : inside)
      for (int r : rows_of_col[col]) local_rows.insert(r);
    std::map<int, int> local;
    for (size_t a = 0; a < inside.size(); ++a) local[inside[a]] = static_cast<int>(a);
    std::vector<std::vector<mpq_class>> dense;
    for (int r : local_rows) {
      std::vector<mpq_class> row(inside.size(), mpq_class(0));
      for (const auto& [col, v] : rows[r])
        if (const auto it = local.find(col); it != local.end()) row[it->second] = v;
      dense.push_back(std::move(row));
    }
    for (auto& v : null_space_exact(std::move(dense), static_cast<int>(inside.size()))) {
      SparseVector f;
      mpq_class largest = 0;
      for (size_t a = 0; a < inside.size(); ++a)
        if (v[a] != 0) {
          f[inside[a]] = v[a];
          largest = std::max(largest, mpq_class(abs(v[a])));
        }
      for (auto& [k, c] : f) c /= largest;
      found.push_back(std::move(f));
    }
    return found;
  };

  std::set<GridBox> tried;
  for (int layer = 0; static_cast<long>(out.size()) < nullity; ++layer) {
    bool grew = false;
    for (GridBox& box : boxes) {
      if (static_cast<long>(out.size()) == nullity) break;
      if (layer > 0)
        box = snap({std::max(box.x0 - 1, 0), std::max(box.y0 - 1, 0), std::min(box.x1 + 1, g.nx()), std::min(box.y1 + 1, g.ny())});
      if (!tried.insert(box).second) continue;
      grew = true;
      for (auto& f : null_vectors(box)) {
        consider(std::move(f));
        if (static_cast<long>(out.size()) == nullity) break;
      }
    }
    if (!grew) break;  // every box is the whole mesh
  }
  if (static_cast<long>(out.size()) != nullity)
    throw std::logic_error("local_null_basis: the boxes' null vectors do not reach the block's nullity");
  return out;
}

}  // namespace

long eliminate_extended_edges(PtSplineBasis& B, const std::vector<EeeRow>& rows, const Grid& g,
                              const RectangularPartition& mesh, long needed) {
  const int columns = static_cast<int>(B.splines.size());
  B.equations = static_cast<long>(rows.size());
  // Independent blocks: B-splines linked by a common equation.
  UnionFind uf(columns);
  std::vector<bool> touched(columns, false);
  for (const auto& r : rows)
    for (const auto& [col, v] : r) {
      touched[col] = true;
      uf.join(col, r.front().first);
    }
  std::map<int, std::vector<int>> block_columns, block_rows;
  for (int col = 0; col < columns; ++col)
    if (touched[col]) block_columns[uf.find(col)].push_back(col);
  for (size_t r = 0; r < rows.size(); ++r) block_rows[uf.find(rows[r].front().first)].push_back(static_cast<int>(r));
  for (int col = 0; col < columns; ++col)
    if (!touched[col]) {
      B.functions.push_back({{col, mpq_class(1)}});
      ++B.untouched;
    }
  // The ranks first: they give the number of functions, and when that falls short of
  // `needed` the null vectors (most of the time of a large block) are not worth computing.
  std::vector<long> ranks;
  long count = B.untouched;
  for (const auto& [root, cols] : block_columns) {
    ++B.blocks;
    B.largest_block = std::max(B.largest_block, static_cast<int>(cols.size()));
    std::vector<SparseRationalRow> sparse;
    for (int r : block_rows[root]) sparse.push_back({{rows[r].begin(), rows[r].end()}});
    // Modular rank <= rank over Q; were it lower, the boxes could not reach the nullity and
    // local_null_basis would throw rather than return too few functions.
    ranks.push_back(rank_reliable(sparse, columns));
    B.rank += ranks.back();
    count += static_cast<long>(cols.size()) - ranks.back();
  }
  if (needed >= 0 && count < needed) {
    B.short_of_dimension = needed - count;
    return count;
  }
  std::vector<GridBox> support(columns);
  for (int col = 0; col < columns; ++col) {
    const auto& sp = B.splines[col];
    support[col] = {g.index_x(sp.x.front()), g.index_y(sp.y.front()), g.index_x(sp.x.back()), g.index_y(sp.y.back())};
  }
  size_t block = 0;
  for (const auto& [root, cols] : block_columns) {
    const long rank = ranks[block++];
    std::vector<SparseVector> null = local_null_basis(cols, block_rows[root], rows, support, g, mesh,
                                                      static_cast<long>(cols.size()) - rank);
    for (const auto& v : null) B.functions.push_back(as_function(v));
  }
  return count;
}

}  // namespace knotwork::pt_detail
