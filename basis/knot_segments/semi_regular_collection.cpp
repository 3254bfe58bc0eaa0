#include "basis/knot_segments/semi_regular_collection.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <functional>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

#include "basis/core/bspline_basis.hpp"
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
};

InducedCells induced_cells(const SplineRefs& splines, const Box& region) {
  std::set<double> sx{region.x0, region.x1}, sy{region.y0, region.y1};
  for (const auto* b : splines) {
    for (double x : b->x)
      if (x > region.x0 && x < region.x1) sx.insert(x);
    for (double y : b->y)
      if (y > region.y0 && y < region.y1) sy.insert(y);
  }
  const std::vector<double> xs(sx.begin(), sx.end()), ys(sy.begin(), sy.end());
  const int nx = static_cast<int>(xs.size()) - 1, ny = static_cast<int>(ys.size()) - 1;
  // Knot line pieces: per value, the union of the intervals the B-splines draw there.
  std::map<double, std::vector<std::pair<double, double>>> vlines, hlines;
  for (const auto* b : splines) {
    for (double x : b->x) vlines[x].emplace_back(b->y.front(), b->y.back());
    for (double y : b->y) hlines[y].emplace_back(b->x.front(), b->x.back());
  }
  for (auto* lines : {&vlines, &hlines})
    for (auto& [v, pieces] : *lines) {
      std::sort(pieces.begin(), pieces.end());
      std::vector<std::pair<double, double>> merged;
      for (const auto& p : pieces)
        if (!merged.empty() && p.first <= merged.back().second)
          merged.back().second = std::max(merged.back().second, p.second);
        else
          merged.push_back(p);
      pieces.swap(merged);
    }
  auto covered = [](const std::map<double, std::vector<std::pair<double, double>>>& lines, double at, double lo,
                    double hi) {
    const auto it = lines.find(at);
    if (it == lines.end()) return false;
    const auto& pieces = it->second;
    auto p = std::upper_bound(pieces.begin(), pieces.end(), std::make_pair(lo, 1e300));
    if (p == pieces.begin()) return false;
    --p;
    return p->first <= lo && hi <= p->second;
  };
  std::vector<int> parent(static_cast<size_t>(nx) * ny);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx && !covered(vlines, xs[i + 1], ys[j], ys[j + 1])) parent[find(i + nx * j)] = find(i + 1 + nx * j);
      if (j + 1 < ny && !covered(hlines, ys[j + 1], xs[i], xs[i + 1])) parent[find(i + nx * j)] = find(i + nx * (j + 1));
    }
  struct Extent {
    int i0, i1, j0, j1, count;
  };
  std::map<int, Extent> groups;
  for (int k = 0; k < nx * ny; ++k) {
    const int i = k % nx, j = k / nx;
    auto [it, fresh] = groups.try_emplace(find(k), Extent{i, i, j, j, 0});
    Extent& e = it->second;
    e.i0 = std::min(e.i0, i);
    e.i1 = std::max(e.i1, i);
    e.j0 = std::min(e.j0, j);
    e.j1 = std::max(e.j1, j);
    ++e.count;
  }
  InducedCells out;
  for (const auto& [root, e] : groups) {
    const Box box{xs[e.i0], ys[e.j0], xs[e.i1 + 1], ys[e.j1 + 1]};
    if (e.count != (e.i1 - e.i0 + 1) * (e.j1 - e.j0 + 1))
      out.problems.push_back("the region around " + describe(box) + " is not a rectangle");
    out.cells.push_back(box);
  }
  std::sort(out.cells.begin(), out.cells.end(), [](const Box& a, const Box& b) {
    return a.y0 != b.y0 ? a.y0 < b.y0 : a.x0 < b.x0;
  });
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

// The B-splines alive on each cell, in increasing index. Testing every B-spline on every cell
// costs cells x functions (a 512^2 grid took 517 s); here the cells are put in the buckets of
// a grid over the domain that they overlap, and each B-spline tests only the cells in the
// buckets its support overlaps. Bucket ranges are taken inclusively (a superset): alive_on
// decides.
std::vector<std::vector<int>> alive_per_cell(const std::vector<LocalBSpline>& splines, const std::vector<Box>& cells,
                                             const Box& domain) {
  const int g = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(cells.size())))));
  const double wx = (domain.x1 - domain.x0) / g, wy = (domain.y1 - domain.y0) / g;
  auto bucket = [g](double t, double t0, double w) {
    const double b = std::floor((t - t0) / w);  // not cast before clamping: NaN or huge values are UB as int
    return b >= 0 && b < g ? static_cast<int>(b) : (b >= g ? g - 1 : 0);
  };
  auto column = [&](double x) { return wx > 0 ? bucket(x, domain.x0, wx) : 0; };
  auto row = [&](double y) { return wy > 0 ? bucket(y, domain.y0, wy) : 0; };
  std::vector<std::vector<int>> buckets(static_cast<size_t>(g) * g);
  for (size_t c = 0; c < cells.size(); ++c)
    for (int j = row(cells[c].y0); j <= row(cells[c].y1); ++j)
      for (int i = column(cells[c].x0); i <= column(cells[c].x1); ++i) buckets[size_t(j) * g + i].push_back(int(c));
  std::vector<std::vector<int>> alive(cells.size());
  std::vector<int> seen(cells.size(), -1);
  for (int k = 0; k < static_cast<int>(splines.size()); ++k) {
    const LocalBSpline& b = splines[k];
    for (int j = row(b.y.front()); j <= row(b.y.back()); ++j)
      for (int i = column(b.x.front()); i <= column(b.x.back()); ++i)
        for (int c : buckets[size_t(j) * g + i])
          if (seen[c] != k) {
            seen[c] = k;
            if (alive_on(b, cells[c])) alive[c].push_back(k);
          }
  }
  return alive;
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
  std::map<std::vector<double>, std::vector<const LocalBSpline*>> groups;
  for (const auto* b : alive) groups[first(b)].push_back(b);
  if (static_cast<int>(groups.size()) != d_first + 1) {
    why = std::to_string(groups.size()) + " distinct " + (x_first ? "horizontal" : "vertical") +
          " knot vectors instead of " + std::to_string(d_first + 1);
    return false;
  }
  // Consecutive windows of one vector V of length 2d+2, the cell in its middle span.
  std::vector<std::vector<double>> windows;
  for (const auto& [v, members] : groups) windows.push_back(v);  // map order = lexicographic = window order
  for (int i = 1; i <= d_first; ++i)  // consecutive windows overlap: W_i[t] = W_{i-1}[t+1]
    for (int t = 0; t <= d_first; ++t)
      if (windows[i][t] != windows[i - 1][t + 1]) {
        why = std::string(x_first ? "horizontal" : "vertical") + " knot vectors are not windows of one vector";
        return false;
      }
  if (!(windows[0][d_first] <= lo && hi <= windows[d_first][1])) {
    why = "the cell is not in the middle span of the shared knot vector";
    return false;
  }
  if (structure) {
    structure->x_first = x_first;
    structure->shared = windows[0];
    structure->shared.insert(structure->shared.end(), windows[d_first].end() - d_first, windows[d_first].end());
    structure->other.clear();
    structure->spline.clear();
  }
  for (const auto& [v, members] : groups) {
    std::vector<std::vector<double>> ws;
    for (const auto* b : members) ws.push_back(second(b));
    std::sort(ws.begin(), ws.end());
    ws.erase(std::unique(ws.begin(), ws.end()), ws.end());
    if (static_cast<int>(ws.size()) != d_second + 1) {
      why = std::to_string(ws.size()) + " B-splines share a " + (x_first ? "horizontal" : "vertical") +
            " knot vector instead of " + std::to_string(d_second + 1);
      return false;
    }
    for (int i = 1; i <= d_second; ++i)
      for (int t = 0; t <= d_second; ++t)
        if (ws[i][t] != ws[i - 1][t + 1]) {
          why = "their other knot vectors are not windows of one vector";
          return false;
        }
    if (!(ws[0][d_second] <= lo2 && hi2 <= ws[d_second][1])) {
      why = "the cell is not in the middle span of a shared knot vector";
      return false;
    }
    if (structure) {
      std::vector<double> full = ws[0];
      full.insert(full.end(), ws[d_second].end() - d_second, ws[d_second].end());
      structure->other.push_back(full);
      std::vector<const LocalBSpline*> ordered;
      for (const auto& w : ws)
        for (const auto* b : members)
          if (second(b) == w) ordered.push_back(b);
      structure->spline.push_back(ordered);
    }
  }
  return true;
}

}  // namespace

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
  if (it == lines.end()) return 0;
  std::vector<double> breaks{lo, hi};
  for (const Piece& p : it->second) {
    if (p.from > lo && p.from < hi) breaks.push_back(p.from);
    if (p.to > lo && p.to < hi) breaks.push_back(p.to);
  }
  std::sort(breaks.begin(), breaks.end());
  int result = 1 << 20;
  for (size_t k = 0; k + 1 < breaks.size(); ++k) {
    if (breaks[k] == breaks[k + 1]) continue;
    const double mid = 0.5 * (breaks[k] + breaks[k + 1]);
    int here = 0;
    for (const Piece& p : it->second)
      if (p.from <= mid && mid <= p.to) here = std::max(here, p.multiplicity);
    result = std::min(result, here);
    if (result == 0) return 0;
  }
  return result;
}

void SemiRegularCollection::split_until_stable(std::vector<LocalBSpline> work, Change& change) {
  // A B-spline whose support a mesh line crosses completely must use that knot with the
  // line's multiplicity (otherwise it would "jump over" it, Def. 3.1): split it by
  // univariate knot insertion into two, and look at the two halves again.
  cache_valid_ = false;
  auto needed_split = [&](const LocalBSpline& b, bool& vertical, double& at) {
    for (int dir = 0; dir < 2; ++dir) {
      const auto& lines = dir == 0 ? vlines_ : hlines_;
      const auto& across = dir == 0 ? b.x : b.y;
      const auto& along = dir == 0 ? b.y : b.x;
      for (auto it = lines.upper_bound(across.front()); it != lines.end() && it->first < across.back(); ++it) {
        const int m = covering_multiplicity(dir == 0, it->first, along.front(), along.back());
        if (m > std::count(across.begin(), across.end(), it->first)) {
          vertical = dir == 0;
          at = it->first;
          return true;
        }
      }
    }
    return false;
  };
  while (!work.empty()) {
    const LocalBSpline b = std::move(work.back());
    work.pop_back();
    bool vertical = true;
    double at = 0;
    if (!set_.count(b) || !needed_split(b, vertical, at)) continue;
    std::vector<double> refined = vertical ? b.x : b.y;
    refined.insert(std::upper_bound(refined.begin(), refined.end(), at), at);
    LocalBSpline left = b, right = b;
    (vertical ? left.x : left.y).assign(refined.begin(), refined.end() - 1);
    (vertical ? right.x : right.y).assign(refined.begin() + 1, refined.end());
    set_.erase(b);
    auto was_added = std::find(change.added.begin(), change.added.end(), b);
    if (was_added != change.added.end())
      change.added.erase(was_added);
    else
      change.removed.push_back(b);
    for (const LocalBSpline& child : {left, right})
      if (set_.insert(child).second) {
        change.added.push_back(child);
        work.push_back(child);
      }
  }
}

void SemiRegularCollection::undo(const Change& change) {
  cache_valid_ = false;
  for (const auto& b : change.added) set_.erase(b);
  set_.insert(change.removed.begin(), change.removed.end());
}

std::string SemiRegularCollection::local_violation(const Change& change) const {
  // Cells whose alive B-splines changed lie in the supports of the removed and added ones;
  // supports are unions of cells, so the partition computed on their bounding box from the
  // B-splines that meet it is exact on every cell inside a changed support.
  std::vector<Box> changed;
  Box region{1e300, 1e300, -1e300, -1e300};
  for (const auto* list : {&change.removed, &change.added})
    for (const auto& b : *list) {
      changed.push_back({b.x.front(), b.y.front(), b.x.back(), b.y.back()});
      region = {std::min(region.x0, b.x.front()), std::min(region.y0, b.y.front()), std::max(region.x1, b.x.back()),
                std::max(region.y1, b.y.back())};
    }
  if (changed.empty()) return {};
  SplineRefs near;
  for (const auto& b : set_)
    if (b.x.front() < region.x1 && b.x.back() > region.x0 && b.y.front() < region.y1 && b.y.back() > region.y0)
      near.push_back(&b);
  const InducedCells ic = induced_cells(near, region);
  if (!ic.problems.empty()) return ic.problems.front();
  for (const Box& c : ic.cells) {
    bool inside = false;
    for (const Box& s : changed) inside = inside || (s.x0 <= c.x0 && c.x1 <= s.x1 && s.y0 <= c.y0 && c.y1 <= s.y1);
    if (!inside) continue;
    SplineRefs alive;
    for (const auto* b : near)
      if (alive_on(*b, c)) alive.push_back(b);
    if (static_cast<int>(alive.size()) != (dx_ + 1) * (dy_ + 1))
      return "cell " + describe(c) + ": " + std::to_string(alive.size()) + " B-splines are alive";
    std::string why_a, why_b;
    if (!regular_in(alive, dx_, dy_, true, c, why_a) && !regular_in(alive, dy_, dx_, false, c, why_b))
      return "cell " + describe(c) + ": neither (a) " + why_a + " nor (b) " + why_b;
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
  // Knot values along the segment's direction: where an extension may stop.
  std::set<double> stops{lo_along, hi_along};
  for (const auto& b : set_)
    for (double v : s.vertical ? b.y : b.x) stops.insert(v);
  const std::vector<Piece> lines_before = lines.count(s.position) ? lines[s.position] : std::vector<Piece>{};
  // Extensions by i knot steps below and j above, tried by increasing i + j (both splits
  // of each total): the first that refines and stays semi-regular is the minimal one.
  const std::vector<double> below(std::make_reverse_iterator(stops.upper_bound(s.from)), stops.rend());
  const std::vector<double> above(stops.lower_bound(s.to), stops.end());
  // below[0] <= s.from is the first stop at or under the start; below[i] i steps further.
  auto start_at = [&](size_t i) { return i == 0 ? s.from : below[below[0] == s.from ? i : i - 1]; };
  auto end_at = [&](size_t j) { return j == 0 ? s.to : above[above[0] == s.to ? j : j - 1]; };
  const size_t max_i = below.empty() ? 0 : (below[0] == s.from ? below.size() - 1 : below.size());
  const size_t max_j = above.empty() ? 0 : (above[0] == s.to ? above.size() - 1 : above.size());
  // Per total, the balanced splits and the one-sided ones (trying every split would cost
  // quadratically many attempts on long extensions).
  for (size_t total = 0; total <= max_i + max_j; ++total) {
    std::vector<size_t> lows;
    const size_t lo_i = total > max_j ? total - max_j : 0, hi_i = std::min(total, max_i);
    if (lo_i > hi_i) continue;
    for (size_t a : {total / 2, (total + 1) / 2, size_t{0}, total}) lows.push_back(std::clamp(a, lo_i, hi_i));
    std::sort(lows.begin(), lows.end());
    lows.erase(std::unique(lows.begin(), lows.end()), lows.end());
    for (size_t i : lows) {
      if (i > max_i || total - i > max_j) continue;
      KnotInsertion seg = s;
      seg.from = start_at(i);
      seg.to = end_at(total - i);
      add_line(seg);
      // The B-splines the new line may cross completely (the rest cascades from their halves).
      std::vector<LocalBSpline> work;
      for (const auto& b : set_) {
        const auto& across = s.vertical ? b.x : b.y;
        const auto& along = s.vertical ? b.y : b.x;
        if (across.front() < s.position && s.position < across.back() && along.back() > seg.from && along.front() < seg.to)
          work.push_back(b);
      }
      Change change;
      split_until_stable(std::move(work), change);
      if (!change.removed.empty() && local_violation(change).empty()) {
        report.inserted = seg;
        report.splits = static_cast<int>(change.removed.size());
        report.extended = seg.from != s.from || seg.to != s.to;
        return report;
      }
      undo(change);
      if (lines_before.empty())
        lines.erase(s.position);
      else
        lines[s.position] = lines_before;
    }
  }
  throw std::runtime_error("a full knot line does not give a semi-regular collection here");
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
  const std::vector<std::vector<int>> alive_ids = alive_per_cell(all, ic.cells, {x0_, y0_, x1_, y1_});
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
// (which contains local's knots): Boehm insertion of the missing knots, then the resulting
// windows located in U. Returns (global index, coefficient) pairs.
std::vector<std::pair<int, double>> in_global_basis(const std::vector<double>& local, const std::vector<double>& U) {
  const int d = static_cast<int>(local.size()) - 2;
  std::vector<double> padded(d, local.front() - 1.0);  // as in single_bspline_bernstein
  padded.insert(padded.end(), local.begin(), local.end());
  padded.insert(padded.end(), d, local.back() + 1.0);
  BSplineBasis1D basis(d, padded);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(2 * d + 1, 1);
  c(d, 0) = 1.0;
  for (size_t i = 0; i < U.size();) {
    size_t j = i;
    while (j < U.size() && U[j] == U[i]) ++j;
    if (U[i] > local.front() && U[i] < local.back()) {
      const long have = std::count(local.begin(), local.end(), U[i]);
      for (long r = have; r < static_cast<long>(j - i); ++r) basis = insert_knot(basis, c, U[i]);
    }
    i = j;
  }
  std::vector<std::pair<int, double>> out;
  const auto& K = basis.knots();
  for (int f = 0; f < basis.num_functions(); ++f) {
    if (c(f, 0) == 0.0) continue;
    const std::vector<double> window(K.begin() + f, K.begin() + f + d + 2);
    for (size_t g = 0; g + d + 2 <= U.size(); ++g)
      if (std::equal(window.begin(), window.end(), U.begin() + g)) {
        out.emplace_back(static_cast<int>(g), c(f, 0));
        break;
      }
  }
  return out;
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
  const std::vector<std::vector<int>> alive = alive_per_cell(all, ic.cells, {x0_, y0_, x1_, y1_});
  for (size_t ci = 0; ci < ic.cells.size(); ++ci) {
    const Box& c = ic.cells[ci];
    const std::vector<int>& ids = alive[ci];
    std::vector<Eigen::VectorXd> bx, by;
    for (int k : ids) {
      bx.push_back(single_bspline_bernstein(all[k].x, c.x0, c.x1));
      by.push_back(single_bspline_bernstein(all[k].y, c.y0, c.y1));
    }
    Eigen::MatrixXd C(ids.size(), nb);
    for (size_t a = 0; a < ids.size(); ++a)
      for (int v = 0; v <= dy_; ++v)
        for (int u = 0; u <= dx_; ++u) C(a, u + (dx_ + 1) * v) = bx[a][u] * by[a][v];
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
