// PT-splines on a minimal extension of T: the l-edges of T are inserted one by one as LR
// meshlines into the tensor mesh of T's cross-cuts, each extended only as far as it must be
// for the insertion to split a B-spline (the LR condition; the paper extends "as little as
// possible", Sec. 3.1, and turns T l-edges into longer ones or rays rather than cross-cuts).
// The LR B-splines of that mesh T^e are the local tensor-product B-splines; a combination is
// in S(T) when it is a single polynomial on every cell of T (the EEE condition, here across
// extended edges of both directions). pt_spline_basis certifies the result (count = the
// dimension of S(T), exact independence) and falls back to the full extension otherwise.
#include <algorithm>
#include <set>

#include "basis/tmesh/lr_spline.hpp"
#include "basis/pt/pt_eee.hpp"

namespace knotwork::pt_detail {

namespace {

// A straight run of edges of T on one grid line, in grid indices: the line x = X[line]
// (vertical; from, to index Y) or y = Y[line].
struct GridSegment {
  bool vertical;
  int line, from, to;
};

// The maximal runs of edges of T on the interior grid lines that do not cross the rectangle.
// (The lines that do, the cross-cuts, make the initial tensor mesh.)
void l_edges(const Grid& g, std::vector<mpq_class>& xs, std::vector<mpq_class>& ys, std::vector<GridSegment>& runs) {
  xs = {g.X.front()}, ys = {g.Y.front()};
  for (int vertical = 1; vertical >= 0; --vertical) {
    const int lines = vertical ? g.nx() : g.ny(), length = vertical ? g.ny() : g.nx();
    for (int l = 1; l < lines; ++l) {
      auto edge = [&](int s) { return vertical ? g.at(l - 1, s) != g.at(l, s) : g.at(s, l - 1) != g.at(s, l); };
      std::vector<GridSegment> found;
      for (int s = 0; s < length;) {
        if (!edge(s)) {
          ++s;
          continue;
        }
        int e = s;
        while (e < length && edge(e)) ++e;
        found.push_back({static_cast<bool>(vertical), l, s, e});
        s = e;
      }
      if (found.size() == 1 && found[0].from == 0 && found[0].to == length) (vertical ? xs : ys).push_back(vertical ? g.X[l] : g.Y[l]);
      else runs.insert(runs.end(), found.begin(), found.end());
    }
  }
  xs.push_back(g.X.back()), ys.push_back(g.Y.back());
}

// The LR-mesh: T's cross-cuts, then its other l-edges, each inserted once both its ends lie on
// meshlines (an l-edge of T ends on a perpendicular l-edge; with T-cycles some must wait for
// none, and then the first is lengthened to meshlines already there), lengthened by one
// vertex at a time, on the side that adds less, until the insertion splits a B-spline.
// The variant sets the order (longest or shortest l-edges first) and how many vertices every
// l-edge is lengthened by on each side beforehand.
// Returns false if some l-edge cannot be inserted even as a full line.
bool build_lr_mesh(const Grid& g, LrMesh& lr, std::vector<GridSegment> pending, const MinimalVariant& variant) {
  auto coordinate = [&](const GridSegment& s, int i) { return s.vertical ? g.Y[i] : g.X[i]; };
  auto position = [&](const GridSegment& s) { return s.vertical ? g.X[s.line] : g.Y[s.line]; };
  auto length = [&](const GridSegment& s) { return s.vertical ? g.ny() : g.nx(); };
  // An end at grid index i is held when a perpendicular meshline (or the boundary) passes there.
  auto held = [&](const GridSegment& s, int i) {
    return i == 0 || i == length(s) || lr.has_line_through(!s.vertical, coordinate(s, i), position(s));
  };
  auto next_held = [&](const GridSegment& s, int i, int step) {
    do i += step;
    while (!held(s, i));
    return i;
  };
  auto covered = [&](const GridSegment& s) {
    for (int i = s.from; i < s.to; ++i) {
      const mpq_class mid = (coordinate(s, i) + coordinate(s, i + 1)) / 2;
      if (!lr.has_line_through(s.vertical, position(s), mid)) return false;
    }
    return true;
  };
  auto try_insert = [&](const GridSegment& s) {
    return lr.try_insert({s.vertical, position(s), coordinate(s, s.from), coordinate(s, s.to)});
  };
  auto insert_lengthened = [&](GridSegment s) {
    for (int e = 0; e < variant.extra_steps; ++e) {
      if (s.from > 0) s.from = next_held(s, s.from, -1);
      if (s.to < length(s)) s.to = next_held(s, s.to, +1);
    }
    for (;;) {
      if (try_insert(s)) return true;
      GridSegment lower = s, upper = s;
      if (s.from > 0) lower.from = next_held(s, s.from, -1);
      if (s.to < length(s)) upper.to = next_held(s, s.to, +1);
      if (s.from == 0 && s.to == length(s)) return false;
      const mpq_class added_lower = coordinate(s, s.from) - coordinate(s, lower.from);
      const mpq_class added_upper = coordinate(s, upper.to) - coordinate(s, s.to);
      const bool lower_first = s.from > 0 && (s.to == length(s) || added_lower <= added_upper);
      for (const GridSegment& t : lower_first ? std::vector{lower, upper} : std::vector{upper, lower})
        if ((t.from != s.from || t.to != s.to) && try_insert(t)) return true;
      s.from = lower.from, s.to = upper.to;
    }
  };
  std::stable_sort(pending.begin(), pending.end(), [&](const GridSegment& a, const GridSegment& b) {
    const mpq_class la = coordinate(a, a.to) - coordinate(a, a.from), lb = coordinate(b, b.to) - coordinate(b, b.from);
    return variant.shortest_first ? la < lb : la > lb;
  });
  while (!pending.empty()) {
    bool progress = false;
    for (size_t k = 0; k < pending.size();) {
      const GridSegment& s = pending[k];
      if (covered(s)) {
        pending.erase(pending.begin() + static_cast<long>(k));
        progress = true;
      } else if (held(s, s.from) && held(s, s.to)) {
        if (!insert_lengthened(s)) return false;
        pending.erase(pending.begin() + static_cast<long>(k));
        progress = true;
      } else {
        ++k;
      }
    }
    if (progress) continue;
    GridSegment s = pending.front();  // every end waits on another: lengthen one l-edge to meshlines
    if (!held(s, s.from)) s.from = next_held(s, s.from, -1);
    if (!held(s, s.to)) s.to = next_held(s, s.to, +1);
    if (!insert_lengthened(s)) return false;
    pending.erase(pending.begin());
  }
  return true;
}

// Whether the B-splines are linearly independent, proved by peeling (Dokken-Lyche-Pettersen's
// overloading argument), or not known. The LR B-splines span every polynomial of bi-degree
// (m, n) (they refine the tensor B-splines of the cross-cuts), so on any piece of the mesh at
// least (m+1)(n+1) of them are nonzero; where exactly that many are, their restrictions are a
// basis of the polynomials, so none of them can carry a coefficient of a vanishing
// combination. Nor can a B-spline that is the only one left on some piece once those are
// excluded. When that excludes every B-spline there is no vanishing combination: they are
// independent. (The pieces: each cell of T cut by the knot lines of the B-splines meeting it.)
bool independent_by_peeling(const std::vector<PtLocalBSpline>& splines, const std::vector<std::vector<int>>& meeting,
                            const RectangularPartition& mesh, int m, int n) {
  const size_t full = static_cast<size_t>(m + 1) * (n + 1);
  std::vector<std::vector<int>> pieces;  // the B-splines nonzero on each piece
  for (int k = 0; k < mesh.num_cells(); ++k) {
    const auto& c = mesh.cells()[k];
    std::vector<mpq_class> cut[2] = {{c.x0, c.x1}, {c.y0, c.y1}};
    for (int s : meeting[k])
      for (int d = 0; d < 2; ++d)
        for (const mpq_class& v : d == 0 ? splines[s].x : splines[s].y)
          if ((d == 0 ? c.x0 : c.y0) < v && v < (d == 0 ? c.x1 : c.y1)) cut[d].push_back(v);
    for (auto& list : cut) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    const int nx = static_cast<int>(cut[0].size()) - 1, ny = static_cast<int>(cut[1].size()) - 1;
    auto index = [](const std::vector<mpq_class>& list, const mpq_class& v) {
      return static_cast<int>(std::lower_bound(list.begin(), list.end(), v) - list.begin());
    };
    const size_t first = pieces.size();
    pieces.resize(first + static_cast<size_t>(nx) * ny);
    for (int s : meeting[k]) {
      const auto& sp = splines[s];
      const int x0 = sp.x.front() <= c.x0 ? 0 : index(cut[0], sp.x.front());
      const int x1 = sp.x.back() >= c.x1 ? nx : index(cut[0], sp.x.back());
      const int y0 = sp.y.front() <= c.y0 ? 0 : index(cut[1], sp.y.front());
      const int y1 = sp.y.back() >= c.y1 ? ny : index(cut[1], sp.y.back());
      for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i) pieces[first + i + static_cast<size_t>(nx) * j].push_back(s);
    }
  }
  std::vector<bool> excluded(splines.size(), false);
  for (const auto& on : pieces) {
    if (on.size() < full) return false;  // cannot happen if they span the polynomials: prove nothing
    if (on.size() == full)
      for (int s : on) excluded[s] = true;
  }
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto& on : pieces) {
      int left = -1, count = 0;
      for (int s : on)
        if (!excluded[s]) left = s, ++count;
      if (count == 1) excluded[left] = true, changed = true;
    }
  }
  return std::all_of(excluded.begin(), excluded.end(), [](bool e) { return e; });
}

}  // namespace

std::optional<PtSplineBasis> build_minimal(const RectangularPartition& mesh, int m, int n, const C0Lines& c0,
                                           const MinimalVariant& variant, long needed) {
  const Grid g = make_grid(mesh);
  std::vector<mpq_class> xs, ys;
  std::vector<GridSegment> runs;
  l_edges(g, xs, ys, runs);
  LrMesh lr(xs, ys, m, n, c0);
  if (!build_lr_mesh(g, lr, runs, variant)) return std::nullopt;

  PtSplineBasis B;
  B.m = m, B.n = n, B.c0 = c0, B.extension = PtExtension::kMinimal;
  B.extension_cells = lr.cells();
  for (const LrBSpline& s : lr.splines()) B.splines.push_back({s.x, s.y});

  // The B-splines meeting each cell of T.
  std::vector<std::vector<int>> meeting(mesh.num_cells());
  for (int s = 0; s < static_cast<int>(B.splines.size()); ++s)
    for (int k : g.cells_under(B.splines[s])) meeting[k].push_back(s);
  // EEE rows, cell by cell: the knot lines of those B-splines inside the cell cut it into a
  // grid on which every one of them is a polynomial. The sum is a polynomial on the cell iff
  // across each such line the jump of the top derivative (d^n/dy^n across y = Y, d^m/dx^m
  // across x = X), a polynomial between consecutive cutting lines, vanishes at deg + 1
  // points of every piece.
  std::vector<EeeRow> rows;
  for (int k = 0; k < mesh.num_cells(); ++k) {
    const auto& c = mesh.cells()[k];
    std::set<mpq_class> inside[2];  // [vertical]
    for (int s : meeting[k]) {
      for (const mpq_class& v : B.splines[s].x)
        if (c.x0 < v && v < c.x1) inside[1].insert(v);
      for (const mpq_class& v : B.splines[s].y)
        if (c.y0 < v && v < c.y1) inside[0].insert(v);
    }
    for (int vertical = 0; vertical < 2; ++vertical) {
      const int deg = vertical ? n : m;  // degree along the line
      std::vector<mpq_class> cuts{vertical ? c.y0 : c.x0};
      cuts.insert(cuts.end(), inside[!vertical].begin(), inside[!vertical].end());
      cuts.push_back(vertical ? c.y1 : c.x1);
      for (const mpq_class& at : inside[vertical]) {
        ++B.extended_edges;
        std::vector<std::pair<int, mpq_class>> jumps;
        for (int s : meeting[k]) {
          const auto& across = vertical ? B.splines[s].x : B.splines[s].y;
          if (!contains(across, at)) continue;
          mpq_class jump = top_derivative_jump(across, at);
          if (jump != 0) jumps.emplace_back(s, std::move(jump));
        }
        for (size_t piece = 0; piece + 1 < cuts.size(); ++piece)
          for (int q = 0; q <= deg; ++q) {
            const mpq_class t = cuts[piece] + (cuts[piece + 1] - cuts[piece]) * (q + 1) / (deg + 2);
            EeeRow row;
            for (const auto& [s, jump] : jumps) {
              mpq_class v = jump * bspline_value<mpq_class>(vertical ? B.splines[s].y : B.splines[s].x, t);
              if (v != 0) row.emplace_back(s, std::move(v));
            }
            if (!row.empty()) rows.push_back(std::move(row));
          }
      }
    }
  }
  eliminate_extended_edges(B, rows, g, mesh, needed);
  if (B.short_of_dimension > 0) return B;  // pt_spline_basis tries another insertion order
  B.splines_independent = independent_by_peeling(B.splines, meeting, mesh, m, n);
  // The untouched B-splines (the first functions) keep their LR weights: where T^e = T they
  // are the weighted LR B-splines, a partition of unity.
  for (int f = 0; f < B.untouched; ++f) B.functions[f].front().second = lr.splines()[B.functions[f].front().first].weight;
  return B;
}

}  // namespace knotwork::pt_detail
