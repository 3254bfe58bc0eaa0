#include "basis/knot_segments/semi_regular_collection.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <functional>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "basis/core/box_index.hpp"

#include "basis/core/bspline_basis.hpp"
#include "basis/core/bspline_kernel.hpp"
#include "basis/tmesh/partition_topology.hpp"

namespace knotwork {

namespace {

struct Box {
  double x0, y0, x1, y1;
};

std::string describe(const Box& b) {
  std::ostringstream s;
  s << "[" << b.x0 << "," << b.x1 << "]x[" << b.y0 << "," << b.y1 << "]";
  return s.str();
}

bool contains(const std::vector<double>& v, double t) { return std::find(v.begin(), v.end(), t) != v.end(); }

using SplineRefs = std::vector<const LocalBSpline*>;

// Cells of the partition induced by the B-splines inside `region`: a fine grid on every knot
// value, with neighbouring fine cells merged unless some B-spline's knot line separates them.
struct InducedCells {
  std::vector<Box> cells;
  std::vector<std::string> problems;  // regions that are not rectangles
  std::vector<double> xs, ys;         // the fine grid: every knot value inside the region
  std::vector<int> cell_of;           // per fine cell (i + nx j), its index in cells
};

InducedCells induced_cells(const SplineRefs& splines, const Box& region) {
  // Sorted vectors rather than sets and maps: this runs for every insertion attempt. The knot
  // values are few and repeat many times (neighbouring B-splines share them): each is looked
  // up in the sorted distinct values so far (sorting them all: 0.25 s more in an adaptive run
  // to 50 000 dofs). Over the whole domain (the Bezier mesh) there are a few thousand at most,
  // so the insertions into the middle stay cheap.
  std::vector<double> xs{region.x0, region.x1}, ys{region.y0, region.y1};
  auto add = [](std::vector<double>& grid, double t) {
    const auto it = std::lower_bound(grid.begin(), grid.end(), t);
    if (*it != t) grid.insert(it, t);  // t lies strictly inside the region: `it` is not the end
  };
  for (const auto* b : splines) {
    for (double x : b->x)
      if (x > region.x0 && x < region.x1) add(xs, x);
    for (double y : b->y)
      if (y > region.y0 && y < region.y1) add(ys, y);
  }
  const int nx = static_cast<int>(xs.size()) - 1, ny = static_cast<int>(ys.size()) - 1;
  // Which fine edges a knot line separates: each B-spline marks the fine edges its knot lines
  // run along over its support (whose ends are grid values or lie outside the region). Marking
  // costs the supports' lengths in fine edges; sorting and merging the line pieces instead was
  // over a quarter of the checks (docs/records/performance-2026-11-22-to-12-04.md, "Adaptive knot segments within 20×").
  auto at_or_after = [](const std::vector<double>& grid, double t) {
    return static_cast<int>(std::lower_bound(grid.begin(), grid.end(), t) - grid.begin());
  };
  // vertical_cut[i + (nx + 1) j]: the edge x = xs[i], ys[j] < y < ys[j+1] is on a knot line.
  std::vector<char> vertical_cut(static_cast<size_t>(nx + 1) * ny, 0), horizontal_cut(static_cast<size_t>(nx) * (ny + 1), 0);
  // Grid indices of a sorted knot vector's values: one search, then a walk (the knots are few
  // and the grid near them is short; a search per knot: 0.9 s more at 50 000 dofs).
  std::vector<int> at_x, at_y;
  auto indices = [&](const std::vector<double>& grid, const std::vector<double>& knots, std::vector<int>& out) {
    out.resize(knots.size());
    int g = at_or_after(grid, knots.front());
    const int n = static_cast<int>(grid.size());
    for (size_t k = 0; k < knots.size(); ++k) {
      while (g < n && grid[g] < knots[k]) ++g;
      out[k] = g;
    }
  };
  for (const auto* b : splines) {
    indices(xs, b->x, at_x);
    indices(ys, b->y, at_y);
    const int i0 = at_x.front(), i1 = std::min(at_x.back(), nx), j0 = at_y.front(), j1 = std::min(at_y.back(), ny);
    for (size_t k = 0; k < b->x.size(); ++k) {
      if (!(b->x[k] > region.x0 && b->x[k] < region.x1)) continue;
      for (int j = j0; j < j1; ++j) vertical_cut[at_x[k] + static_cast<size_t>(nx + 1) * j] = 1;
    }
    for (size_t k = 0; k < b->y.size(); ++k) {
      if (!(b->y[k] > region.y0 && b->y[k] < region.y1)) continue;
      for (int i = i0; i < i1; ++i) horizontal_cut[i + static_cast<size_t>(nx) * at_y[k]] = 1;
    }
  }
  std::vector<int> parent(static_cast<size_t>(nx) * ny);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx && !vertical_cut[i + 1 + static_cast<size_t>(nx + 1) * j]) parent[find(i + nx * j)] = find(i + 1 + nx * j);
      if (j + 1 < ny && !horizontal_cut[i + static_cast<size_t>(nx) * (j + 1)]) parent[find(i + nx * j)] = find(i + nx * (j + 1));
    }
  struct Extent {
    int i0, i1, j0, j1, count;
  };
  std::vector<int> group_of_root(parent.size(), -1);
  std::vector<Extent> extents;
  for (int k = 0; k < nx * ny; ++k) {
    const int i = k % nx, j = k / nx, r = find(k);
    if (group_of_root[r] < 0) {
      group_of_root[r] = static_cast<int>(extents.size());
      extents.push_back({i, i, j, j, 0});
    }
    Extent& e = extents[group_of_root[r]];
    e.i0 = std::min(e.i0, i);
    e.i1 = std::max(e.i1, i);
    e.j0 = std::min(e.j0, j);
    e.j1 = std::max(e.j1, j);
    ++e.count;
  }
  InducedCells out;
  std::vector<std::pair<Box, int>> boxes;  // with the group, to number the fine cells after sorting
  for (size_t g = 0; g < extents.size(); ++g) {
    const Extent& e = extents[g];
    const Box box{xs[e.i0], ys[e.j0], xs[e.i1 + 1], ys[e.j1 + 1]};
    if (e.count != (e.i1 - e.i0 + 1) * (e.j1 - e.j0 + 1))
      out.problems.push_back("the region around " + describe(box) + " is not a rectangle");
    boxes.emplace_back(box, static_cast<int>(g));
  }
  std::sort(boxes.begin(), boxes.end(), [](const auto& a, const auto& b) {
    return a.first.y0 != b.first.y0 ? a.first.y0 < b.first.y0 : a.first.x0 < b.first.x0;
  });
  std::vector<int> index_of_group(extents.size());
  for (const auto& [box, g] : boxes) {
    index_of_group[g] = static_cast<int>(out.cells.size());
    out.cells.push_back(box);
  }
  out.cell_of.resize(parent.size());
  for (int k = 0; k < nx * ny; ++k) out.cell_of[k] = index_of_group[group_of_root[find(k)]];
  out.xs = std::move(xs);
  out.ys = std::move(ys);
  return out;
}

SplineRefs refs(const std::vector<LocalBSpline>& splines) {
  SplineRefs r;
  r.reserve(splines.size());
  for (const auto& b : splines) r.push_back(&b);
  return r;
}

bool alive_on(const LocalBSpline& b, const Box& c) {
  return b.x.front() <= c.x0 && c.x1 <= b.x.back() && b.y.front() <= c.y0 && c.y1 <= b.y.back();
}

Box support(const LocalBSpline& b) { return {b.x.front(), b.y.front(), b.x.back(), b.y.back()}; }

// For each cell of `ic`, the boxes (in increasing index) that contain it. Each box visits the
// fine-grid cells it covers (the grid holds every knot value, so its ends are grid values or
// lie outside the region), so the cost is the boxes' areas in fine cells — about (p+1)(q+1)
// times the fine grid for supports — not cells x boxes (a 512^2 grid took 517 s that way),
// and graded meshes cost no more than uniform ones.
// Per cell, a list of indices, stored in one array (with a vector per cell containing_boxes
// took twice as long in an adaptive run to 50 000 dofs).
struct CellLists {
  std::vector<int> start, items;  // cell c's list: items[start[c]], ..., items[start[c + 1] - 1]
  std::span<const int> operator[](size_t c) const { return {items.data() + start[c], items.data() + start[c + 1]}; }
};

// `wanted` (if given): a flag per cell; the lists of the other cells are left empty.
CellLists containing_boxes(const std::vector<Box>& boxes, const InducedCells& ic, const std::vector<char>* wanted = nullptr) {
  const int nx = static_cast<int>(ic.xs.size()) - 1;
  auto first_at_or_after = [](const std::vector<double>& grid, double t) {
    return static_cast<int>(std::lower_bound(grid.begin(), grid.end(), t) - grid.begin());
  };
  std::vector<std::pair<int, int>> found;  // (cell, box), boxes increasing
  std::vector<int> seen(ic.cells.size(), -1);
  for (int k = 0; k < static_cast<int>(boxes.size()); ++k) {
    const Box& b = boxes[k];
    const int i0 = std::max(0, first_at_or_after(ic.xs, b.x0)), i1 = std::min(nx, first_at_or_after(ic.xs, b.x1));
    const int j0 = std::max(0, first_at_or_after(ic.ys, b.y0));
    const int j1 = std::min(static_cast<int>(ic.ys.size()) - 1, first_at_or_after(ic.ys, b.y1));
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i) {
        const int c = ic.cell_of[static_cast<size_t>(j) * nx + i];
        if (seen[c] == k || (wanted && !(*wanted)[c])) continue;
        seen[c] = k;
        const Box& cell = ic.cells[c];
        if (b.x0 <= cell.x0 && cell.x1 <= b.x1 && b.y0 <= cell.y0 && cell.y1 <= b.y1) found.emplace_back(c, k);
      }
  }
  // A counting sort by cell keeps each cell's boxes in increasing order.
  CellLists out;
  out.start.assign(ic.cells.size() + 1, 0);
  for (const auto& [c, k] : found) ++out.start[c + 1];
  std::partial_sum(out.start.begin(), out.start.end(), out.start.begin());
  out.items.resize(found.size());
  std::vector<int> next(out.start.begin(), out.start.end() - 1);
  for (const auto& [c, k] : found) out.items[next[c]++] = k;
  return out;
}

// The B-splines alive on each cell, in increasing index.
CellLists alive_per_cell(const std::vector<LocalBSpline>& splines, const InducedCells& ic) {
  std::vector<Box> supports;
  supports.reserve(splines.size());
  for (const auto& b : splines) supports.push_back(support(b));
  return containing_boxes(supports, ic);
}

// What Def. 3.3 finds on a cell: the shared vector (X in case a) and, per window i of it,
// the other vector (Y^(i)) with the B-splines in window order: spline[i][j] = N_i N_j.
struct CellStructure {
  bool x_first = true;
  std::vector<double> shared;
  std::vector<std::vector<double>> other;
  std::vector<std::vector<const LocalBSpline*>> spline;
};

// Def. 3.3 (2a) for one cell: the alive B-splines are N_i(X|x) N_j(Y^(i)|y) with X of length
// 2d+2 whose windows are the distinct x vectors, and per window a Y^(i) likewise. `first`
// selects the coordinate that must be shared (x for case a, y for case b).
bool regular_in(const std::vector<const LocalBSpline*>& alive, int d_first, int d_second, bool x_first,
                const Box& c, std::string& why, CellStructure* structure = nullptr) {
  auto first = [&](const LocalBSpline* b) -> const std::vector<double>& { return x_first ? b->x : b->y; };
  auto second = [&](const LocalBSpline* b) -> const std::vector<double>& { return x_first ? b->y : b->x; };
  const double lo = x_first ? c.x0 : c.y0, hi = x_first ? c.x1 : c.y1;
  const double lo2 = x_first ? c.y0 : c.x0, hi2 = x_first ? c.y1 : c.x1;
  // Sorted by (first, second) vector, the B-splines sharing a first vector are consecutive
  // and in window order of their second vectors; no vector is copied (this runs for every
  // changed cell of every insertion attempt).
  std::vector<const LocalBSpline*> sorted(alive);
  std::sort(sorted.begin(), sorted.end(), [&](const LocalBSpline* a, const LocalBSpline* b) {
    const int order = first(a) < first(b) ? -1 : (first(b) < first(a) ? 1 : 0);
    return order != 0 ? order < 0 : second(a) < second(b);
  });
  std::vector<size_t> starts;  // of the groups sharing a first vector, then the end
  for (size_t k = 0; k < sorted.size(); ++k)
    if (k == 0 || first(sorted[k]) != first(sorted[k - 1])) starts.push_back(k);
  const int groups = static_cast<int>(starts.size());
  starts.push_back(sorted.size());
  if (groups != d_first + 1) {
    why = std::to_string(groups) + " distinct " + (x_first ? "horizontal" : "vertical") + " knot vectors instead of " +
          std::to_string(d_first + 1);
    return false;
  }
  // Consecutive windows of one vector V of length 2d+2, the cell in its middle span.
  auto window = [&](int i) -> const std::vector<double>& { return first(sorted[starts[i]]); };
  for (int i = 1; i <= d_first; ++i)  // consecutive windows overlap: W_i[t] = W_{i-1}[t+1]
    for (int t = 0; t <= d_first; ++t)
      if (window(i)[t] != window(i - 1)[t + 1]) {
        why = std::string(x_first ? "horizontal" : "vertical") + " knot vectors are not windows of one vector";
        return false;
      }
  if (!(window(0)[d_first] <= lo && hi <= window(d_first)[1])) {
    why = "the cell is not in the middle span of the shared knot vector";
    return false;
  }
  if (structure) {
    structure->x_first = x_first;
    structure->shared = window(0);
    structure->shared.insert(structure->shared.end(), window(d_first).end() - d_first, window(d_first).end());
    structure->other.clear();
    structure->spline.clear();
  }
  for (int g = 0; g < groups; ++g) {
    // Distinct B-splines with one first vector have distinct second vectors.
    const size_t begin = starts[g], count = starts[g + 1] - begin;
    if (static_cast<int>(count) != d_second + 1) {
      why = std::to_string(count) + " B-splines share a " + (x_first ? "horizontal" : "vertical") +
            " knot vector instead of " + std::to_string(d_second + 1);
      return false;
    }
    auto ws = [&](int i) -> const std::vector<double>& { return second(sorted[begin + i]); };
    for (int i = 1; i <= d_second; ++i)
      for (int t = 0; t <= d_second; ++t)
        if (ws(i)[t] != ws(i - 1)[t + 1]) {
          why = "their other knot vectors are not windows of one vector";
          return false;
        }
    if (!(ws(0)[d_second] <= lo2 && hi2 <= ws(d_second)[1])) {
      why = "the cell is not in the middle span of a shared knot vector";
      return false;
    }
    if (structure) {
      std::vector<double> full = ws(0);
      full.insert(full.end(), ws(d_second).end() - d_second, ws(d_second).end());
      structure->other.push_back(full);
      structure->spline.emplace_back(sorted.begin() + begin, sorted.begin() + begin + count);
    }
  }
  return true;
}

// The same decision as regular_in, without sorting or messages: the check of every insertion
// attempt (in an adaptive run to 50 000 dofs regular_in took 1.7 s of the checks' 6 s, this
// 0.8 s). On a cell in the middle span of V, the window V[i..i+d+1] has the cell in its span
// d - i, so each alive B-spline's place in the grid (i, j) is read off the spans that hold the
// cell; regular_in's sorted order is this order (windows of a non-decreasing vector increase
// lexicographically), and a place taken twice or a span outside 0..d is a failure regular_in
// also finds. test_semi_regular checks every refinement against violations(), which uses
// regular_in.
bool regular_quick(const SplineRefs& alive, int d_first, int d_second, bool x_first, const Box& c,
                   std::vector<const LocalBSpline*>& place) {
  auto first = [&](const LocalBSpline* b) -> const std::vector<double>& { return x_first ? b->x : b->y; };
  auto second = [&](const LocalBSpline* b) -> const std::vector<double>& { return x_first ? b->y : b->x; };
  const double lo = x_first ? c.x0 : c.y0, hi = x_first ? c.x1 : c.y1;
  const double lo2 = x_first ? c.y0 : c.x0, hi2 = x_first ? c.y1 : c.x1;
  auto span_of = [](const std::vector<double>& v, double a, double b) {
    for (size_t k = 0; k + 1 < v.size(); ++k)
      if (v[k] <= a && b <= v[k + 1] && v[k] < v[k + 1]) return static_cast<int>(k);
    return -1;
  };
  const int n2 = d_second + 1;
  place.assign(static_cast<size_t>(d_first + 1) * n2, nullptr);
  if (alive.size() != place.size()) return false;  // then some place stays empty
  for (const LocalBSpline* b : alive) {
    const int k1 = span_of(first(b), lo, hi), k2 = span_of(second(b), lo2, hi2);
    if (k1 < 0 || k1 > d_first || k2 < 0 || k2 > d_second) return false;
    const LocalBSpline*& slot = place[static_cast<size_t>(d_first - k1) * n2 + (d_second - k2)];
    if (slot) return false;
    slot = b;
  }
  auto at = [&](int i, int j) { return place[static_cast<size_t>(i) * n2 + j]; };
  for (int i = 0; i <= d_first; ++i) {
    for (int j = 1; j <= d_second; ++j)
      if (first(at(i, j)) != first(at(i, 0))) return false;
    if (i > 0)
      for (int t = 0; t <= d_first; ++t)
        if (first(at(i, 0))[t] != first(at(i - 1, 0))[t + 1]) return false;
    for (int j = 1; j <= d_second; ++j)
      for (int t = 0; t <= d_second; ++t)
        if (second(at(i, j))[t] != second(at(i, j - 1))[t + 1]) return false;
  }
  // regular_in's last condition, the cell in the middle span of the shared vectors, holds by
  // construction: the B-spline at place (i, j) has the cell in span d_first - i of its first
  // vector and d_second - j of its second.
  return true;
}

}  // namespace

namespace {
using SupportTree = BoxIndex<double, const LocalBSpline*>;
SupportTree::Box index_box(const LocalBSpline& b) { return SupportTree::box(b.x.front(), b.y.front(), b.x.back(), b.y.back()); }
}  // namespace

struct SemiRegularCollection::SupportIndex {
  SupportTree tree;
};

SemiRegularCollection::SupportIndex& SemiRegularCollection::index() const {
  if (!index_.value) {
    std::vector<SupportTree::Entry> values;
    values.reserve(set_.size());
    for (const auto& b : set_) values.emplace_back(index_box(b), &b);
    index_.value = std::make_shared<SupportIndex>(SupportIndex{SupportTree(values)});  // packed bulk load
  }
  return *index_.value;
}

std::vector<const LocalBSpline*> SemiRegularCollection::meeting(double x0, double y0, double x1, double y1) const {
  std::vector<const LocalBSpline*> out;
  index().tree.intersecting(SupportTree::box(x0, y0, x1, y1), out);
  return out;
}

void SemiRegularCollection::erase_spline(std::set<LocalBSpline>::const_iterator it) {
  if (index_.value) index_.value->tree.remove(index_box(*it), &*it);
  set_.erase(it);
}

const LocalBSpline* SemiRegularCollection::insert_spline(const LocalBSpline& b) {
  const auto [it, fresh] = set_.insert(b);
  if (!fresh) return nullptr;
  if (index_.value) index_.value->tree.insert(index_box(*it), &*it);
  return &*it;
}

SemiRegularCollection SemiRegularCollection::tensor_product(int dx, int dy, const std::vector<double>& bx,
                                                            const std::vector<double>& by, const std::vector<int>& mx,
                                                            const std::vector<int>& my) {
  if (dx < 1 || dy < 1) throw std::invalid_argument("degrees must be >= 1");
  if (bx.size() < 2 || by.size() < 2) throw std::invalid_argument("need at least two breakpoints per direction");
  for (size_t i = 1; i < bx.size(); ++i)
    if (!(bx[i] > bx[i - 1])) throw std::invalid_argument("x breakpoints must increase");
  for (size_t i = 1; i < by.size(); ++i)
    if (!(by[i] > by[i - 1])) throw std::invalid_argument("y breakpoints must increase");
  SemiRegularCollection c;
  c.dx_ = dx;
  c.dy_ = dy;
  c.x0_ = bx.front();
  c.x1_ = bx.back();
  c.y0_ = by.front();
  c.y1_ = by.back();
  auto multiplicity = [](const std::vector<int>& m, size_t i, int d) {
    const int r = i - 1 < m.size() ? m[i - 1] : 1;
    if (r < 1 || r > d) throw std::invalid_argument("interior multiplicity must be in [1, degree]");
    return r;
  };
  auto open = [&](int d, const std::vector<double>& b, const std::vector<int>& m) {
    std::vector<double> U(d + 1, b.front());
    for (size_t i = 1; i + 1 < b.size(); ++i) U.insert(U.end(), multiplicity(m, i, d), b[i]);
    U.insert(U.end(), d + 1, b.back());
    return U;
  };
  const auto U = open(dx, bx, mx), V = open(dy, by, my);
  for (size_t j = 0; j + dy + 1 < V.size(); ++j)
    for (size_t i = 0; i + dx + 1 < U.size(); ++i)
      c.set_.insert({std::vector<double>(U.begin() + i, U.begin() + i + dx + 2),
                     std::vector<double>(V.begin() + j, V.begin() + j + dy + 2)});
  for (size_t i = 1; i + 1 < bx.size(); ++i) c.add_line({true, bx[i], c.y0_, c.y1_, multiplicity(mx, i, dx)});
  for (size_t j = 1; j + 1 < by.size(); ++j) c.add_line({false, by[j], c.x0_, c.x1_, multiplicity(my, j, dy)});
  return c;
}

bool interior_knots_simple(const std::vector<LocalBSpline>& splines) {
  for (const auto& b : splines)
    for (const auto* v : {&b.x, &b.y})
      for (size_t i = 1; i < v->size(); ++i)
        if ((*v)[i] == (*v)[i - 1] && (*v)[i] != v->front() && (*v)[i] != v->back()) return false;
  return true;
}

SemiRegularCollection SemiRegularCollection::from_splines(int dx, int dy, std::vector<LocalBSpline> splines) {
  if (splines.empty()) throw std::invalid_argument("the collection is empty");
  SemiRegularCollection c;
  c.dx_ = dx;
  c.dy_ = dy;
  c.x0_ = c.y0_ = 1e300;
  c.x1_ = c.y1_ = -1e300;
  for (size_t k = 0; k < splines.size(); ++k) {
    const auto& b = splines[k];
    if (static_cast<int>(b.x.size()) != dx + 2 || static_cast<int>(b.y.size()) != dy + 2)
      throw std::invalid_argument("B-spline " + std::to_string(k) + " needs " + std::to_string(dx + 2) + " x-knots and " +
                                  std::to_string(dy + 2) + " y-knots");
    if (!std::is_sorted(b.x.begin(), b.x.end()) || !std::is_sorted(b.y.begin(), b.y.end()) ||
        !(b.x.back() > b.x.front() && b.y.back() > b.y.front()))
      throw std::invalid_argument("B-spline " + std::to_string(k) + " has knots that do not increase");
    c.x0_ = std::min(c.x0_, b.x.front());
    c.x1_ = std::max(c.x1_, b.x.back());
    c.y0_ = std::min(c.y0_, b.y.front());
    c.y1_ = std::max(c.y1_, b.y.back());
  }
  // The mesh lines are the B-splines' own interior knots (with the multiplicity each uses),
  // so that later insertions split across them like across inserted ones.
  for (const auto& b : splines) {
    for (int dir = 0; dir < 2; ++dir) {
      const auto& across = dir == 0 ? b.x : b.y;
      const auto& along = dir == 0 ? b.y : b.x;
      for (size_t i = 0; i < across.size();) {
        size_t j = i;
        while (j < across.size() && across[j] == across[i]) ++j;
        const bool inside = dir == 0 ? (across[i] > c.x0_ && across[i] < c.x1_) : (across[i] > c.y0_ && across[i] < c.y1_);
        if (inside && across[i] > across.front() && across[i] < across.back())
          c.add_line({dir == 0, across[i], along.front(), along.back(), static_cast<int>(j - i)});
        i = j;
      }
    }
  }
  c.set_.insert(splines.begin(), splines.end());
  if (c.set_.size() != splines.size()) throw std::invalid_argument("the collection lists a B-spline twice");
  // Insertions check only the new line for the B-splines it crosses, which needs every
  // B-spline to use every line that crosses it, with its multiplicity (violations() checks
  // Def. 3.1 for presence only). A start that does not is refined as before, every line.
  double unused = 0;
  c.stable_ = std::none_of(c.set_.begin(), c.set_.end(), [&](const LocalBSpline& b) {
    return c.jumped_line(b, true, unused) || c.jumped_line(b, false, unused);
  });
  return c;
}

const std::vector<LocalBSpline>& SemiRegularCollection::splines() const {
  const std::lock_guard<std::mutex> guard(*cache_lock_);
  if (!cache_valid_) {
    cache_.assign(set_.begin(), set_.end());
    cache_valid_ = true;
  }
  return cache_;
}

void SemiRegularCollection::add_line(const KnotInsertion& s) {
  auto& pieces = (s.vertical ? vlines_ : hlines_)[s.position];
  Piece p{s.from, s.to, s.multiplicity};
  // Merge with touching or overlapping pieces of the same multiplicity.
  for (auto it = pieces.begin(); it != pieces.end();) {
    if (it->multiplicity == p.multiplicity && it->from <= p.to && p.from <= it->to) {
      p.from = std::min(p.from, it->from);
      p.to = std::max(p.to, it->to);
      it = pieces.erase(it);
    } else {
      ++it;
    }
  }
  pieces.push_back(p);
}

int SemiRegularCollection::covering_multiplicity(bool vertical, double position, double lo, double hi) const {
  const auto& lines = vertical ? vlines_ : hlines_;
  const auto it = lines.find(position);
  return it == lines.end() ? 0 : covering_multiplicity(it->second, lo, hi);
}

int SemiRegularCollection::covering_multiplicity(const std::vector<Piece>& pieces, double lo, double hi) {
  // Most lines a B-spline's range meets do not cover its start (they are knots of refined
  // regions elsewhere along it): answered without building the breaks.
  if (lo < hi && std::none_of(pieces.begin(), pieces.end(), [&](const Piece& p) { return p.from <= lo && lo < p.to; }))
    return 0;
  std::vector<double> breaks{lo, hi};
  for (const Piece& p : pieces) {
    if (p.from > lo && p.from < hi) breaks.push_back(p.from);
    if (p.to > lo && p.to < hi) breaks.push_back(p.to);
  }
  std::sort(breaks.begin(), breaks.end());
  int result = 1 << 20;
  for (size_t k = 0; k + 1 < breaks.size(); ++k) {
    if (breaks[k] == breaks[k + 1]) continue;
    const double mid = 0.5 * (breaks[k] + breaks[k + 1]);
    int here = 0;
    for (const Piece& p : pieces)
      if (p.from <= mid && mid <= p.to) here = std::max(here, p.multiplicity);
    result = std::min(result, here);
    if (result == 0) return 0;
  }
  return result;
}

bool SemiRegularCollection::jumps(const LocalBSpline& b, bool vertical, double position,
                                  const std::vector<Piece>& pieces) {
  const auto& across = vertical ? b.x : b.y;
  const auto& along = vertical ? b.y : b.x;
  return covering_multiplicity(pieces, along.front(), along.back()) > std::count(across.begin(), across.end(), position);
}

bool SemiRegularCollection::jumped_line(const LocalBSpline& b, bool vertical, double& position) const {
  const auto& lines = vertical ? vlines_ : hlines_;
  const auto& across = vertical ? b.x : b.y;
  for (auto it = lines.upper_bound(across.front()); it != lines.end() && it->first < across.back(); ++it)
    if (jumps(b, vertical, it->first, it->second)) {
      position = it->first;
      return true;
    }
  return false;
}

namespace {

// B-spline b with the knot `at` inserted across x (vertical) or y: its first and its last
// knots, the two B-splines univariate knot insertion splits it into (a split and its replay in
// prolongation_from make them here).
std::array<LocalBSpline, 2> halves_at(const LocalBSpline& b, bool vertical, double at) {
  std::vector<double> refined = vertical ? b.x : b.y;
  refined.insert(std::upper_bound(refined.begin(), refined.end(), at), at);
  std::array<LocalBSpline, 2> out{b, b};
  (vertical ? out[0].x : out[0].y).assign(refined.begin(), refined.end() - 1);
  (vertical ? out[1].x : out[1].y).assign(refined.begin() + 1, refined.end());
  return out;
}

}  // namespace

void SemiRegularCollection::split_until_stable(std::vector<LocalBSpline> start, const KnotInsertion& inserted,
                                               Change& change) {
  // A B-spline whose support a mesh line crosses completely must use that knot with the
  // line's multiplicity (otherwise it would "jump over" it, Def. 3.1): split it by
  // univariate knot insertion into two, and look at the two halves again.
  //
  // Which lines can a B-spline jump over? Before the insertion none (the collection was
  // stable: stable_), so the B-splines the new line crosses need checking at its position
  // only. The halves of a B-spline split at x = t keep its y range and get x ranges inside
  // its own, with every knot strictly inside them as often as in the parent: they jump over
  // no vertical line the parent used, but may over a horizontal line too short to cross the
  // parent, and over x = t again if its multiplicity is higher. So a half checks every line
  // across the split and only the listed positions along it, unless its parent had to check
  // them all. The same lines are found first as by looking at every line in the support's
  // range (the listed ones are the only ones that can fail, and are tried in the same order),
  // with half the lines looked at (81 → 37 million in an adaptive run to 50 000 dofs).
  struct Pending {
    LocalBSpline spline;
    std::array<bool, 2> every_line{false, false};  // per direction (0: vertical lines)
    std::vector<double> positions[2];              // else only these, increasing
  };
  std::vector<Pending> work;
  work.reserve(start.size());
  for (LocalBSpline& b : start) {
    Pending p{std::move(b), {!stable_, !stable_}, {}};  // an unstable start: every line, as before
    p.positions[inserted.vertical ? 0 : 1] = {inserted.position};
    work.push_back(std::move(p));
  }
  cache_valid_ = false;
  auto needed_split = [&](const Pending& p, int& dir_out, double& at) {
    const LocalBSpline& b = p.spline;
    for (int dir = 0; dir < 2; ++dir) {
      const auto& lines = dir == 0 ? vlines_ : hlines_;
      const auto& across = dir == 0 ? b.x : b.y;
      if (p.every_line[dir]) {
        if (jumped_line(b, dir == 0, at)) {
          dir_out = dir;
          return true;
        }
        continue;
      }
      for (double t : p.positions[dir]) {
        if (!(across.front() < t && t < across.back())) continue;
        const auto it = lines.find(t);
        if (it != lines.end() && jumps(b, dir == 0, it->first, it->second)) {
          dir_out = dir;
          at = t;
          return true;
        }
      }
    }
    return false;
  };
  while (!work.empty()) {
    Pending p = std::move(work.back());
    work.pop_back();
    int dir = 0;
    double at = 0;
    if (!needed_split(p, dir, at)) continue;
    const auto it = set_.find(p.spline);
    if (it == set_.end()) continue;
    const bool vertical = dir == 0;
    std::array<LocalBSpline, 2> halves = halves_at(p.spline, vertical, at);
    if (recording_) change.splits.push_back({p.spline, vertical, at});
    if (change.added.erase(&*it) == 0) change.removed.push_back(std::move(p.spline));
    erase_spline(it);
    for (LocalBSpline& half : halves) {
      const LocalBSpline* inserted_half = insert_spline(half);
      if (!inserted_half) continue;  // already in the collection
      change.added.insert(inserted_half);
      // Its lines to check: every line across the split, and along it the parent's list
      // (or all, as the parent) with the split's position.
      Pending next{std::move(half), p.every_line, {}};
      next.every_line[1 - dir] = true;
      auto& along = next.positions[dir];
      along = p.positions[dir];
      if (!std::binary_search(along.begin(), along.end(), at)) along.insert(std::upper_bound(along.begin(), along.end(), at), at);
      work.push_back(std::move(next));
    }
  }
}

void SemiRegularCollection::undo(const Change& change) {
  cache_valid_ = false;
  for (const LocalBSpline* b : change.added) erase_spline(set_.find(*b));
  for (const auto& b : change.removed) insert_spline(b);
}

std::string SemiRegularCollection::local_violation(const Change& change, std::array<double, 4>* where,
                                                   const KnotInsertion* segment) const {
  // Cells whose alive B-splines changed lie in the supports of the removed and added ones.
  std::vector<const LocalBSpline*> changed;
  for (const auto& b : change.removed) changed.push_back(&b);
  for (const LocalBSpline* b : change.added) changed.push_back(b);
  if (changed.empty()) return {};
  if (segment) {
    // An extension that fails usually fails at one of its ends: the supports there are checked
    // first, so a failing attempt on a long line costs the size of its ends, not its length.
    auto holds = [](const std::vector<double>& along, double t) { return along.front() <= t && t <= along.back(); };
    std::vector<const LocalBSpline*> ends;
    for (const LocalBSpline* b : changed) {
      const auto& along = segment->vertical ? b->y : b->x;
      if (holds(along, segment->from) || holds(along, segment->to)) ends.push_back(b);
    }
    if (!ends.empty() && ends.size() < changed.size())
      if (std::string why = violation_in(ends, where); !why.empty()) return why;
  }
  return violation_in(changed, where);
}

std::string SemiRegularCollection::violation_in(const std::vector<const LocalBSpline*>& splines,
                                                std::array<double, 4>* where) const {
  // Supports are unions of cells, so the partition computed on the bounding box of the changed
  // supports from the B-splines that meet it is exact on every cell inside one of them.
  std::vector<Box> changed;
  for (const LocalBSpline* b : splines) changed.push_back(support(*b));
  Box region{1e300, 1e300, -1e300, -1e300};
  for (const Box& b : changed)
    region = {std::min(region.x0, b.x0), std::min(region.y0, b.y0), std::max(region.x1, b.x1), std::max(region.y1, b.y1)};
  SplineRefs near;
  std::vector<Box> near_supports;
  for (const LocalBSpline* b : meeting(region.x0, region.y0, region.x1, region.y1))
    if (b->x.front() < region.x1 && b->x.back() > region.x0 && b->y.front() < region.y1 && b->y.back() > region.y0) {
      near.push_back(b);
      near_supports.push_back(support(*b));
    }
  const InducedCells ic = induced_cells(near, region);
  if (!ic.problems.empty()) return ic.problems.front();
  // Only the cells inside a changed support are checked: their alive B-splines are counted.
  const CellLists in_changed = containing_boxes(changed, ic);
  std::vector<char> checked(ic.cells.size());
  for (size_t ci = 0; ci < ic.cells.size(); ++ci) checked[ci] = !in_changed[ci].empty();
  const CellLists alive_ids = containing_boxes(near_supports, ic, &checked);
  SplineRefs alive, place;
  for (size_t ci = 0; ci < ic.cells.size(); ++ci) {
    if (!checked[ci]) continue;
    const Box& c = ic.cells[ci];
    if (static_cast<int>(alive_ids[ci].size()) != (dx_ + 1) * (dy_ + 1)) {
      if (where) *where = {c.x0, c.y0, c.x1, c.y1};
      return "cell " + describe(c) + ": " + std::to_string(alive_ids[ci].size()) + " B-splines are alive";
    }
    alive.clear();
    for (int k : alive_ids[ci]) alive.push_back(near[k]);
    if (!regular_quick(alive, dx_, dy_, true, c, place) && !regular_quick(alive, dy_, dx_, false, c, place)) {
      if (where) *where = {c.x0, c.y0, c.x1, c.y1};
      return "cell " + describe(c) + ": neither (a) nor (b) of Def. 3.3 holds";
    }
  }
  return {};
}

InsertionReport SemiRegularCollection::insert(const KnotInsertion& s) {
  const double lo_across = s.vertical ? x0_ : y0_, hi_across = s.vertical ? x1_ : y1_;
  const double lo_along = s.vertical ? y0_ : x0_, hi_along = s.vertical ? y1_ : x1_;
  if (!(s.position > lo_across && s.position < hi_across))
    throw std::invalid_argument("segment position is not inside the domain");
  if (!(s.from < s.to)) throw std::invalid_argument("segment has zero length");
  if (s.from < lo_along || s.to > hi_along) throw std::invalid_argument("segment leaves the domain");
  const int degree = s.vertical ? dx_ : dy_;
  if (s.multiplicity < 1 || s.multiplicity > degree + 1)
    throw std::invalid_argument("multiplicity " + std::to_string(s.multiplicity) + " is outside [1, degree+1] = [1, " +
                                std::to_string(degree + 1) + "]");
  auto& lines = s.vertical ? vlines_ : hlines_;
  if (const auto it = lines.find(s.position); it != lines.end())
    for (const Piece& L : it->second)
      if (std::min(L.to, s.to) > std::max(L.from, s.from) && L.multiplicity != s.multiplicity)
        throw std::invalid_argument("segment overlaps an existing knot of multiplicity " + std::to_string(L.multiplicity));
  InsertionReport report;
  report.requested = report.inserted = s;
  if (covering_multiplicity(s.vertical, s.position, s.from, s.to) >= s.multiplicity) return report;  // already there
  const std::vector<Piece> lines_before = lines.count(s.position) ? lines[s.position] : std::vector<Piece>{};
  // An extension is i knot steps below and j above; extension_ says in which order they are
  // tried (the header); every candidate is split and checked, and the first that refines
  // and stays semi-regular is kept. below[0] <= s.from is the first stop at or under the
  // start, below[i] i steps further; likewise above. Found when the segment as requested has
  // failed (most insertions need no extension, and the stops take a query along the whole line).
  std::vector<double> below, above;
  size_t max_i = 0, max_j = 0;
  auto find_stops = [&] {
    // Only the knots of the B-splines the whole line crosses: an end between two of them
    // splits the same B-splines as an end at the nearer one.
    std::vector<double> stops{lo_along, hi_along};
    for (const LocalBSpline* b : s.vertical ? meeting(s.position, y0_, s.position, y1_) : meeting(x0_, s.position, x1_, s.position)) {
      const auto& across = s.vertical ? b->x : b->y;
      if (!(across.front() < s.position && s.position < across.back())) continue;
      for (double v : s.vertical ? b->y : b->x) stops.push_back(v);
    }
    std::sort(stops.begin(), stops.end());
    stops.erase(std::unique(stops.begin(), stops.end()), stops.end());
    const auto first_above_from = std::upper_bound(stops.begin(), stops.end(), s.from);
    below.assign(std::make_reverse_iterator(first_above_from), stops.rend());
    above.assign(std::lower_bound(stops.begin(), stops.end(), s.to), stops.end());
    max_i = below.empty() ? 0 : (below[0] == s.from ? below.size() - 1 : below.size());
    max_j = above.empty() ? 0 : (above[0] == s.to ? above.size() - 1 : above.size());
  };
  auto start_at = [&](size_t i) { return i == 0 ? s.from : below[below[0] == s.from ? i : i - 1]; };
  auto end_at = [&](size_t j) { return j == 0 ? s.to : above[above[0] == s.to ? j : j - 1]; };
  // One attempt: insert [start_at(i), end_at(j)], split, check; undone unless it refines and
  // stays semi-regular. `where` gets the failing cell (NaN when nothing was split or the
  // changed region is not a partition into rectangles).
  Change applied;  // what the last successful attempt changed, until it is kept or reverted
  // The kept attempt's splits join the record when insert returns (not when it throws).
  struct KeepSplits {
    SemiRegularCollection& self;
    const Change& kept;
    const int exceptions = std::uncaught_exceptions();
    ~KeepSplits() {
      if (self.recording_ && std::uncaught_exceptions() == exceptions)
        self.splits_.insert(self.splits_.end(), kept.splits.begin(), kept.splits.end());
    }
  } keep_splits{*this, applied};
  auto revert = [&] {
    undo(applied);
    applied = Change{};
    if (lines_before.empty())
      lines.erase(s.position);
    else
      lines[s.position] = lines_before;
  };
  auto attempt = [&](size_t i, size_t j, std::array<double, 4>& where) {
    KnotInsertion seg = s;
    seg.from = start_at(i);
    seg.to = end_at(j);
    add_line(seg);
    // The B-splines the new line crosses completely without using it (the rest cascades from
    // their halves). Most B-splines it meets it does not cross: they are not copied. (From an
    // unstable start, every B-spline it meets, as before.)
    std::vector<LocalBSpline> work;
    const std::vector<Piece>& here = lines.at(s.position);
    for (const LocalBSpline* b : s.vertical ? meeting(s.position, seg.from, s.position, seg.to)
                                            : meeting(seg.from, s.position, seg.to, s.position)) {
      const auto& across = s.vertical ? b->x : b->y;
      const auto& along = s.vertical ? b->y : b->x;
      if (across.front() < s.position && s.position < across.back() && along.back() > seg.from && along.front() < seg.to &&
          (!stable_ || jumps(*b, s.vertical, s.position, here)))
        work.push_back(*b);
    }
    applied = Change{};
    split_until_stable(std::move(work), seg, applied);
    where.fill(std::nan(""));
    if (!applied.removed.empty() && local_violation(applied, &where, &seg).empty()) {
      report.inserted = seg;
      report.splits = static_cast<int>(applied.removed.size());
      report.extended = seg.from != s.from || seg.to != s.to;
      return true;
    }
    revert();
    return false;
  };
  std::array<double, 4> where{};
  if (extension_ == Extension::kMinimal) {
    if (attempt(0, 0, where)) return report;
    find_stops();  // the collection is as it was before the attempt
    // By increasing i + j: per total, the balanced splits and the one-sided ones (trying every
    // split would cost quadratically many attempts on long extensions).
    for (size_t total = 1; total <= max_i + max_j; ++total) {
      std::vector<size_t> lows;
      const size_t lo_i = total > max_j ? total - max_j : 0, hi_i = std::min(total, max_i);
      if (lo_i > hi_i) continue;
      for (size_t a : {total / 2, (total + 1) / 2, size_t{0}, total}) lows.push_back(std::clamp(a, lo_i, hi_i));
      std::sort(lows.begin(), lows.end());
      lows.erase(std::unique(lows.begin(), lows.end()), lows.end());
      for (size_t i : lows) {
        if (i > max_i || total - i > max_j) continue;
        if (attempt(i, total - i, where)) return report;
      }
    }
    throw std::runtime_error("a full knot line does not give a semi-regular collection here");
  }
  // Grown towards the trouble: after a failed attempt, the end nearer the failing cell
  // moves one stop outwards (both ends when nothing was split or no cell is named). Each
  // attempt moves an end, so at most max_i + max_j + 1 attempts, the last a full line.
  size_t i = 0, j = 0, prev_i = 0, prev_j = 0, step_i = 1, step_j = 1;
  const bool gallop = extension_ == Extension::kGalloping;
  while (true) {
    if (attempt(i, j, where)) {
      if (!gallop) return report;
      // The last move may have jumped several stops at one end: bisect back between the
      // failed and the successful position (each probe checked; the smallest success kept).
      const bool low_end = i - prev_i > 1;
      size_t fail = low_end ? prev_i : prev_j, ok = low_end ? i : j;
      bool ok_applied = true;
      while (ok - fail > 1) {
        const size_t mid = fail + (ok - fail) / 2;
        if (ok_applied) revert();
        if (attempt(low_end ? mid : i, low_end ? j : mid, where)) {
          ok = mid;
          ok_applied = true;
        } else {
          fail = mid;
          ok_applied = false;
        }
      }
      if (!ok_applied && !attempt(low_end ? ok : i, low_end ? j : ok, where))
        throw std::logic_error("knot segment insertion: an extension that was semi-regular is not on a second try");
      return report;
    }
    if (i == 0 && j == 0) find_stops();  // after the first attempt, undone: the collection as it was
    if (i == max_i && j == max_j) break;
    const double mid = s.vertical ? 0.5 * (where[1] + where[3]) : 0.5 * (where[0] + where[2]);
    const double from = start_at(i), to = end_at(j);
    const bool grow_low = std::isnan(mid) || mid - from <= to - mid, grow_high = std::isnan(mid) || mid - from >= to - mid;
    const bool low = i < max_i && (grow_low || j == max_j), high = j < max_j && (grow_high || i == max_i);
    prev_i = i;
    prev_j = j;
    if (gallop && low != high) {
      // Galloping: an end that has to move again moves twice as far as last time.
      size_t& step = low ? step_i : step_j;
      size_t& other = low ? step_j : step_i;
      other = 1;
      (low ? i : j) = std::min(low ? max_i : max_j, (low ? i : j) + step);
      step *= 2;
    } else {
      step_i = step_j = 1;
      i += low;
      j += high;
    }
  }
  throw std::runtime_error("a full knot line does not give a semi-regular collection here");
}

void SemiRegularCollection::record_splits(bool on) {
  recording_ = on;
  splits_.clear();
}

Eigen::SparseMatrix<double> SemiRegularCollection::prolongation_from(const SemiRegularCollection& coarse) const {
  if (!recording_) throw std::logic_error("knot segments prolongation: the refinement's splits were not recorded");
  const std::vector<LocalBSpline>& fine = splines();
  const std::vector<LocalBSpline>& rough = coarse.splines();
  // The splits by the B-spline split, sorted once (any one split of a B-spline will do: each
  // is an identity B = a B_left + b B_right); both collections list their B-splines sorted.
  std::vector<int> by_spline(splits_.size());
  std::iota(by_spline.begin(), by_spline.end(), 0);
  std::stable_sort(by_spline.begin(), by_spline.end(), [&](int a, int b) { return splits_[a].from < splits_[b].from; });
  const auto split_of = [&](const LocalBSpline& f) -> const SplitRecord* {
    const auto it = std::lower_bound(by_spline.begin(), by_spline.end(), f, [&](int k, const LocalBSpline& g) { return splits_[k].from < g; });
    return it != by_spline.end() && splits_[*it].from == f ? &splits_[*it] : nullptr;
  };
  const auto fine_index = [&](const LocalBSpline& f) {
    const auto it = std::lower_bound(fine.begin(), fine.end(), f);
    return it != fine.end() && *it == f ? static_cast<int>(it - fine.begin()) : -1;
  };
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(rough.size());
  std::vector<std::pair<LocalBSpline, double>> work;
  for (int j = 0; j < static_cast<int>(rough.size()); ++j) {
    if (const int i = fine_index(rough[j]); i >= 0) {  // kept
      entries.emplace_back(i, j, 1.0);
      continue;
    }
    work.assign(1, {rough[j], 1.0});
    while (!work.empty()) {
      auto [f, c] = std::move(work.back());
      work.pop_back();
      if (const SplitRecord* split = split_of(f)) {
        const auto [a, b] = bspline_kernel::split_weights<double>(split->vertical ? f.x : f.y, split->at);
        auto [left, right] = halves_at(f, split->vertical, split->at);
        work.push_back({std::move(left), c * a});
        work.push_back({std::move(right), c * b});
        continue;
      }
      const int i = fine_index(f);
      if (i < 0) throw std::logic_error("knot segments prolongation: a B-spline of the coarse collection is neither split nor kept");
      entries.emplace_back(i, j, c);
    }
  }
  Eigen::SparseMatrix<double> P(static_cast<Eigen::Index>(fine.size()), static_cast<Eigen::Index>(rough.size()));
  P.setFromTriplets(entries.begin(), entries.end());  // pieces reached twice are summed
  return P;
}

RectangularPartition SemiRegularCollection::partition() const {
  const InducedCells ic = induced_cells(refs(splines()), {x0_, y0_, x1_, y1_});
  if (!ic.problems.empty()) throw std::runtime_error(ic.problems.front());
  std::vector<RationalBox> cells;
  for (const auto& b : ic.cells) cells.push_back({mpq_class(b.x0), mpq_class(b.y0), mpq_class(b.x1), mpq_class(b.y1)});
  return RectangularPartition(cells);
}

std::vector<Violation> SemiRegularCollection::violations() const {
  std::vector<Violation> out;
  const InducedCells ic = induced_cells(refs(splines()), {x0_, y0_, x1_, y1_});
  for (const auto& p : ic.problems) out.push_back({-1, p});
  if (!out.empty()) return out;
  // Def. 3.1 (2): no B-spline jumps over a knot of the partition that cuts its support.
  const PartitionTopology topo = partition_topology(partition());
  for (size_t k = 0; k < splines().size(); ++k) {
    const LocalBSpline& b = splines()[k];
    for (const auto& knot : topo.knots) {
      const double c = knot.position.get_d();
      const double from = (knot.vertical ? topo.vertices[knot.vertices.front()].y : topo.vertices[knot.vertices.front()].x).get_d();
      const double to = (knot.vertical ? topo.vertices[knot.vertices.back()].y : topo.vertices[knot.vertices.back()].x).get_d();
      const std::vector<double>& across = knot.vertical ? b.x : b.y;
      const std::vector<double>& along = knot.vertical ? b.y : b.x;
      if (across.front() < c && c < across.back() && from <= along.front() && along.back() <= to && !contains(across, c)) {
        std::ostringstream s;
        s << "B-spline " << k << " jumps over the " << (knot.vertical ? "vertical" : "horizontal") << " knot at "
          << (knot.vertical ? "x = " : "y = ") << c << " that cuts its support (Def. 3.1)";
        out.push_back({-1, s.str()});
      }
    }
  }
  // Def. 3.3, cell by cell.
  const std::vector<LocalBSpline>& all = splines();
  const CellLists alive_ids = alive_per_cell(all, ic);
  for (size_t ci = 0; ci < ic.cells.size(); ++ci) {
    const Box& c = ic.cells[ci];
    std::vector<const LocalBSpline*> alive;
    for (int k : alive_ids[ci]) alive.push_back(&all[k]);
    std::string why_a, why_b;
    if (static_cast<int>(alive.size()) != (dx_ + 1) * (dy_ + 1)) {
      out.push_back({static_cast<int>(ci), "cell " + describe(c) + ": " + std::to_string(alive.size()) +
                                               " B-splines are alive, not " + std::to_string((dx_ + 1) * (dy_ + 1))});
      continue;
    }
    if (regular_in(alive, dx_, dy_, true, c, why_a) || regular_in(alive, dy_, dx_, false, c, why_b)) continue;
    out.push_back({static_cast<int>(ci), "cell " + describe(c) + ": neither (a) " + why_a + " nor (b) " + why_b});
  }
  return out;
}

double SemiRegularCollection::evaluate(std::span<const double> coefficients, double x, double y) const {
  if (static_cast<int>(coefficients.size()) != size())
    throw std::invalid_argument("evaluate: one coefficient per B-spline is needed");
  if (!(x >= x0_ && x <= x1_ && y >= y0_ && y <= y1_)) throw std::invalid_argument("evaluate: point outside the domain");
  const InducedCells ic = induced_cells(refs(splines()), {x0_, y0_, x1_, y1_});
  // A point on a knot belongs to the cell above / to the right (Weller, Sec. 3); on the
  // domain's top or right side, to the cell below / to the left.
  const Box* cell = nullptr;
  for (const Box& c : ic.cells)
    if ((c.x0 <= x && (x < c.x1 || (x == x1_ && c.x1 == x1_))) && (c.y0 <= y && (y < c.y1 || (y == y1_ && c.y1 == y1_)))) {
      cell = &c;
      break;
    }
  if (!cell) throw std::runtime_error("evaluate: no cell contains the point");
  std::vector<const LocalBSpline*> alive;
  for (const auto& b : splines())
    if (alive_on(b, *cell)) alive.push_back(&b);
  CellStructure st;
  std::string why;
  if (static_cast<int>(alive.size()) != (dx_ + 1) * (dy_ + 1) ||
      !(regular_in(alive, dx_, dy_, true, *cell, why, &st) || regular_in(alive, dy_, dx_, false, *cell, why, &st)))
    throw std::runtime_error("evaluate: the collection is not semi-regular on cell " + describe(*cell));
  const int d_first = st.x_first ? dx_ : dy_, d_second = st.x_first ? dy_ : dx_;
  const double t_first = st.x_first ? x : y, t_second = st.x_first ? y : x;
  // Eq. (3.5): b_i = sum_j b_ij N_j(Y^(i) | y), one univariate de Boor run per i; then (3.4).
  std::vector<double> b(d_first + 1);
  for (int i = 0; i <= d_first; ++i) {
    std::vector<double> cij(d_second + 1);
    for (int j = 0; j <= d_second; ++j) cij[j] = coefficients[st.spline[i][j] - splines().data()];
    b[i] = de_boor(BSplineBasis1D(d_second, st.other[i]), cij, t_second);
  }
  return de_boor(BSplineBasis1D(d_first, st.shared), b, t_first);
}

namespace {

// Global knot vector: every value used, with the largest multiplicity any B-spline gives it.
std::vector<double> global_knots(const std::vector<LocalBSpline>& splines, bool x) {
  std::map<double, int> mult;
  for (const auto& b : splines) {
    const auto& k = x ? b.x : b.y;
    for (size_t i = 0; i < k.size();) {
      size_t j = i;
      while (j < k.size() && k[j] == k[i]) ++j;
      mult[k[i]] = std::max(mult[k[i]], static_cast<int>(j - i));
      i = j;
    }
  }
  std::vector<double> U;
  for (const auto& [v, m] : mult) U.insert(U.end(), m, v);
  return U;
}

// Coefficients of the single B-spline N(local | t) in the basis of the global knot vector U
// (which contains local's knots): (global index, coefficient) pairs.
std::vector<std::pair<int, double>> in_global_basis(const std::vector<double>& local, const std::vector<double>& U) {
  return bspline_kernel::in_finer_knots(local, U);
}

}  // namespace

double TensorProductSpline::operator()(double x, double y) const {
  const int p = basis_x.degree(), q = basis_y.degree();
  const int sx = basis_x.find_span(x), sy = basis_y.find_span(y);
  std::vector<double> nx(p + 1), ny(q + 1);
  basis_x.evaluate(sx, x, nx.data());
  basis_y.evaluate(sy, y, ny.data());
  double v = 0;
  for (int j = 0; j <= q; ++j)
    for (int i = 0; i <= p; ++i) v += coefficients(sx - p + i, sy - q + j) * nx[i] * ny[j];
  return v;
}

TensorProductSpline SemiRegularCollection::to_tensor_product(std::span<const double> coefficients) const {
  if (static_cast<int>(coefficients.size()) != size())
    throw std::invalid_argument("to_tensor_product: one coefficient per B-spline is needed");
  TensorProductSpline t{BSplineBasis1D(dx_, global_knots(splines(), true)), BSplineBasis1D(dy_, global_knots(splines(), false)),
                        Eigen::MatrixXd()};
  t.coefficients = Eigen::MatrixXd::Zero(t.basis_x.num_functions(), t.basis_y.num_functions());
  for (int k = 0; k < size(); ++k) {
    const auto ax = in_global_basis(splines()[k].x, t.basis_x.knots());
    const auto ay = in_global_basis(splines()[k].y, t.basis_y.knots());
    for (const auto& [i, a] : ax)
      for (const auto& [j, b] : ay) t.coefficients(i, j) += coefficients[k] * a * b;
  }
  return t;
}

std::vector<InsertionReport> SemiRegularCollection::refine_cells(const std::vector<int>& cells) {
  return refine_cells(cells, std::vector<Split>(cells.size(), kSplitBoth));
}

std::vector<InsertionReport> SemiRegularCollection::refine_cells(const std::vector<int>& cells,
                                                                 const std::vector<Split>& split) {
  if (split.size() != cells.size()) throw std::invalid_argument("refine_cells: one split direction per cell");
  const InducedCells ic = induced_cells(refs(splines()), {x0_, y0_, x1_, y1_});
  std::vector<InsertionReport> reports;
  for (size_t k = 0; k < cells.size(); ++k) {
    const int i = cells[k];
    if (i < 0 || i >= static_cast<int>(ic.cells.size())) throw std::invalid_argument("no cell " + std::to_string(i));
    const Box& c = ic.cells[i];
    if (split[k] & kSplitX) reports.push_back(insert({true, 0.5 * (c.x0 + c.x1), c.y0, c.y1, 1}));
    if (split[k] & kSplitY) reports.push_back(insert({false, 0.5 * (c.y0 + c.y1), c.x0, c.x1, 1}));
  }
  return reports;
}

BezierMesh SemiRegularCollection::bezier_mesh() const {
  const std::vector<LocalBSpline>& all = splines();
  const InducedCells ic = induced_cells(refs(all), {x0_, y0_, x1_, y1_});
  if (!ic.problems.empty()) throw std::runtime_error(ic.problems.front());
  BezierMesh mesh;
  mesh.set_num_functions(size());
  mesh.set_boundary_names({"bottom", "right", "top", "left"});
  const int nb = (dx_ + 1) * (dy_ + 1);
  const CellLists alive = alive_per_cell(all, ic);
  // Many B-splines share a knot vector in one direction, and many cells an interval: each
  // univariate piece is computed once (measured: bezier_mesh was a fifth of an adaptive run).
  // The knot vectors are numbered first, so that a piece is found by (number, interval)
  // without comparing or copying vectors (that lookup was a third of bezier_mesh at 50 000 dofs).
  std::vector<int> x_id(all.size()), y_id(all.size());
  {
    std::map<std::vector<double>, int> x_ids, y_ids;
    for (size_t k = 0; k < all.size(); ++k) {
      x_id[k] = x_ids.try_emplace(all[k].x, static_cast<int>(x_ids.size())).first->second;
      y_id[k] = y_ids.try_emplace(all[k].y, static_cast<int>(y_ids.size())).first->second;
    }
  }
  struct PieceKey {
    int direction, knots;
    double a, b;
    bool operator==(const PieceKey&) const = default;
  };
  struct PieceHash {
    size_t operator()(const PieceKey& k) const {
      const std::hash<double> h;
      return (static_cast<size_t>(k.knots) * 2 + k.direction) ^ (h(k.a) * 0x9e3779b97f4a7c15ULL) ^ (h(k.b) << 1);
    }
  };
  std::unordered_map<PieceKey, size_t, PieceHash> piece_at;  // offset into `values`
  std::vector<double> values;
  auto piece = [&](int direction, int k, double a, double b) {
    const std::vector<double>& knots = direction == 0 ? all[k].x : all[k].y;
    const auto [it, fresh] = piece_at.try_emplace({direction, direction == 0 ? x_id[k] : y_id[k], a, b}, values.size());
    if (fresh) {
      const Eigen::VectorXd p = single_bspline_bernstein(knots, a, b);
      values.insert(values.end(), p.data(), p.data() + p.size());
    }
    return it->second;
  };
  std::vector<size_t> bx, by;
  for (size_t ci = 0; ci < ic.cells.size(); ++ci) {
    const Box& c = ic.cells[ci];
    const std::span<const int> ids = alive[ci];
    bx.clear();
    by.clear();
    for (int k : ids) {
      bx.push_back(piece(0, k, c.x0, c.x1));
      by.push_back(piece(1, k, c.y0, c.y1));
    }
    Eigen::MatrixXd C(ids.size(), nb);
    for (size_t a = 0; a < ids.size(); ++a)
      for (int v = 0; v <= dy_; ++v)
        for (int u = 0; u <= dx_; ++u) C(a, u + (dx_ + 1) * v) = values[bx[a] + u] * values[by[a] + v];
    BezierCell cell;
    cell.u0 = c.x0;
    cell.u1 = c.x1;
    cell.v0 = c.y0;
    cell.v1 = c.y1;
    cell.degree_u = dx_;
    cell.degree_v = dy_;
    if (c.y0 == y0_) cell.boundary[kSideBottom] = 0;
    if (c.x1 == x1_) cell.boundary[kSideRight] = 1;
    if (c.y1 == y1_) cell.boundary[kSideTop] = 2;
    if (c.x0 == x0_) cell.boundary[kSideLeft] = 3;
    mesh.add_cell(cell, ids, mesh.add_extraction(std::move(C)));
  }
  return mesh;
}

}  // namespace knotwork
