#include "basis/tmesh/rectangular_partition.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <stdexcept>

namespace knotwork {

mpq_class parse_rational(const std::string& text) {
  std::string t = text;
  t.erase(std::remove_if(t.begin(), t.end(), [](unsigned char c) { return std::isspace(c); }), t.end());
  if (t.empty()) throw std::invalid_argument("empty number");
  const auto slash = t.find('/');
  const auto dot = t.find('.');
  auto integer = [&](const std::string& s) {  // optional sign, then at least one digit
    const size_t start = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
    if (s.size() == start || s.find_first_not_of("0123456789", start) != std::string::npos)
      throw std::invalid_argument("\"" + text + "\" is not a number");
    return mpz_class(s[0] == '+' ? s.substr(1) : s);
  };
  mpq_class r;
  if (slash != std::string::npos) {
    const mpz_class den = integer(t.substr(slash + 1));
    if (den == 0) throw std::invalid_argument("\"" + text + "\" divides by zero");
    r = mpq_class(integer(t.substr(0, slash)), den);
  } else if (dot != std::string::npos) {
    const std::string frac = t.substr(dot + 1);
    if (frac.find_first_not_of("0123456789") != std::string::npos)
      throw std::invalid_argument("\"" + text + "\" is not a number");
    std::string whole = t.substr(0, dot);
    if (whole.empty() || whole == "-" || whole == "+") whole += "0";
    mpz_class scale = 1;
    for (size_t i = 0; i < frac.size(); ++i) scale *= 10;
    const bool negative = whole[0] == '-';
    const mpz_class w = integer(whole), f = frac.empty() ? mpz_class(0) : mpz_class(frac);
    const mpz_class numerator = negative ? mpz_class(w * scale - f) : mpz_class(w * scale + f);
    r = mpq_class(numerator, scale);
  } else {
    r = mpq_class(integer(t));
  }
  r.canonicalize();
  return r;
}

namespace {
std::string num(const mpq_class& q) { return q.get_str(); }
std::string box(const RationalBox& b) {
  return "[" + num(b.x0) + ", " + num(b.y0) + ", " + num(b.x1) + ", " + num(b.y1) + "]";
}
}  // namespace

RectangularPartition::RectangularPartition(std::vector<RationalBox> cells) : cells_(std::move(cells)) {
  if (cells_.empty()) throw std::invalid_argument("the partition has no cells");
  // GMP compares only canonical fractions correctly; mpq_class(a, b) is not canonical.
  for (auto& c : cells_)
    for (mpq_class* v : {&c.x0, &c.y0, &c.x1, &c.y1}) v->canonicalize();
  mpq_class X0 = cells_[0].x0, Y0 = cells_[0].y0, X1 = cells_[0].x1, Y1 = cells_[0].y1, area = 0;
  for (size_t i = 0; i < cells_.size(); ++i) {
    const RationalBox& c = cells_[i];
    if (!(c.x1 > c.x0 && c.y1 > c.y0))
      throw std::invalid_argument("cell " + std::to_string(i) + " " + box(c) + " has zero or negative area");
    X0 = std::min(X0, c.x0); Y0 = std::min(Y0, c.y0);
    X1 = std::max(X1, c.x1); Y1 = std::max(Y1, c.y1);
    area += (c.x1 - c.x0) * (c.y1 - c.y0);
  }
  // Sides on each line x = const (vertical) or y = const: (from, to, cell), left or lower
  // sides of cells in [0], right or upper ones in [1]. Sorting them makes the checks and the
  // shared edges O(N log N); comparing every pair of cells took seconds at 10^4 cells.
  struct Side {
    mpq_class from, to;
    int cell;
  };
  std::map<mpq_class, std::array<std::vector<Side>, 2>> lines[2];
  for (int i = 0; i < num_cells(); ++i) {
    const RationalBox& c = cells_[i];
    lines[0][c.x0][0].push_back({c.y0, c.y1, i});
    lines[0][c.x1][1].push_back({c.y0, c.y1, i});
    lines[1][c.y0][0].push_back({c.x0, c.x1, i});
    lines[1][c.y1][1].push_back({c.x0, c.x1, i});
  }
  for (auto& by_position : lines)
    for (auto& [position, sides] : by_position)
      for (auto& list : sides)
        std::sort(list.begin(), list.end(), [](const Side& a, const Side& b) { return a.from < b.from; });
  // The number of cells covering a point changes across a line by (cells starting there) -
  // (cells ending there). If that is zero along every interior line, the count is the same
  // everywhere inside the bounding rectangle, and the areas adding up make it 1: a tiling.
  auto balanced = [&]() {
    for (int d = 0; d < 2; ++d)
      for (const auto& [position, sides] : lines[d]) {
        if (position == (d == 0 ? X0 : Y0) || position == (d == 0 ? X1 : Y1)) continue;
        std::vector<std::pair<mpq_class, int>> events;
        for (const Side& s : sides[0]) events.emplace_back(s.from, 1), events.emplace_back(s.to, -1);
        for (const Side& s : sides[1]) events.emplace_back(s.from, -1), events.emplace_back(s.to, 1);
        std::sort(events.begin(), events.end());
        int sum = 0;
        for (size_t e = 0; e < events.size(); ++e) {
          sum += events[e].second;
          if (sum != 0 && (e + 1 == events.size() || events[e + 1].first != events[e].first)) return false;
        }
      }
    return true;
  };
  if (area != (X1 - X0) * (Y1 - Y0) || !balanced()) {
    // Not a tiling: name two overlapping cells if there are (the slow scan, only here).
    for (size_t i = 0; i < cells_.size(); ++i)
      for (size_t j = i + 1; j < cells_.size(); ++j) {
        const RationalBox &a = cells_[i], &b = cells_[j];
        if (std::min(a.x1, b.x1) > std::max(a.x0, b.x0) && std::min(a.y1, b.y1) > std::max(a.y0, b.y0))
          throw std::invalid_argument("cells " + std::to_string(i) + " " + box(a) + " and " + std::to_string(j) + " " +
                                      box(b) + " overlap");
      }
    // No overlaps, so the union is the bounding rectangle exactly when the areas add up.
    throw std::invalid_argument("the cells do not tile the rectangle [" + num(X0) + ", " + num(X1) + "] x [" +
                                num(Y0) + ", " + num(Y1) + "]: they leave a gap of area " +
                                num(mpq_class((X1 - X0) * (Y1 - Y0) - area)));
  }
  // Shared edges: on each line, the right (upper) sides of some cells against the left (lower)
  // sides of others, both sorted along the line: a merge.
  for (int d = 0; d < 2; ++d)
    for (const auto& [position, sides] : lines[d]) {
      const auto &ending = sides[1], &starting = sides[0];
      size_t a = 0, b = 0;
      while (a < ending.size() && b < starting.size()) {
        const mpq_class lo = std::max(ending[a].from, starting[b].from), hi = std::min(ending[a].to, starting[b].to);
        if (hi > lo) edges_.push_back({ending[a].cell, starting[b].cell, d == 0, position, lo, hi});
        if (ending[a].to < starting[b].to) ++a;
        else ++b;
      }
    }
  // The order of the pairwise scan this replaced: by first cell, then second.
  std::sort(edges_.begin(), edges_.end(), [](const SharedEdge& a, const SharedEdge& b) {
    return a.first != b.first ? a.first < b.first : a.second < b.second;
  });
}

}  // namespace knotwork

namespace knotwork {

std::vector<RationalBox> grid_cells(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys) {
  for (const auto* L : {&xs, &ys}) {
    if (L->size() < 2) throw std::invalid_argument("a grid needs at least two coordinates per direction");
    for (size_t i = 1; i < L->size(); ++i)
      if (!((*L)[i] > (*L)[i - 1]))
        throw std::invalid_argument(std::string("grid ") + (L == &xs ? "x" : "y") + " coordinates must increase (" +
                                    num((*L)[i - 1]) + " then " + num((*L)[i]) + ")");
  }
  std::vector<RationalBox> cells;
  for (size_t j = 0; j + 1 < ys.size(); ++j)
    for (size_t i = 0; i + 1 < xs.size(); ++i) cells.push_back({xs[i], ys[j], xs[i + 1], ys[j + 1]});
  return cells;
}

std::vector<mpq_class> open_knot_vector(const std::vector<mpq_class>& interior, const mpq_class& a, const mpq_class& b,
                                        int p) {
  std::vector<mpq_class> t(p + 1, a);
  t.insert(t.end(), interior.begin(), interior.end());
  t.insert(t.end(), p + 1, b);
  return t;
}

std::vector<RationalBox> insert_segments(std::vector<RationalBox> cells, const std::vector<AxisSegment>& segments) {
  if (segments.empty()) return cells;
  mpq_class X0 = cells.at(0).x0, Y0 = cells[0].y0, X1 = cells[0].x1, Y1 = cells[0].y1;
  for (auto& c : cells) {
    for (mpq_class* v : {&c.x0, &c.y0, &c.x1, &c.y1}) v->canonicalize();
    X0 = std::min(X0, c.x0); Y0 = std::min(Y0, c.y0);
    X1 = std::max(X1, c.x1); Y1 = std::max(Y1, c.y1);
  }
  std::vector<AxisSegment> segs(segments);
  auto name = [&](size_t k) {
    const AxisSegment& s = segs[k];
    return "segment " + std::to_string(k) + " (" + (s.vertical ? "x = " : "y = ") + num(s.position) + " from " +
           num(s.from) + " to " + num(s.to) + ")";
  };
  for (size_t k = 0; k < segs.size(); ++k) {
    AxisSegment& s = segs[k];
    for (mpq_class* v : {&s.position, &s.from, &s.to}) v->canonicalize();
    if (!(s.to > s.from)) throw std::invalid_argument(name(k) + " has zero or negative length");
    const mpq_class &a0 = s.vertical ? X0 : Y0, &a1 = s.vertical ? X1 : Y1;
    const mpq_class &b0 = s.vertical ? Y0 : X0, &b1 = s.vertical ? Y1 : X1;
    if (!(a0 < s.position && s.position < a1 && b0 <= s.from && s.to <= b1))
      throw std::invalid_argument(name(k) + " does not lie inside the rectangle of the mesh (or lies on its boundary)");
  }
  // All segments cut at once, so a segment may end on any other one, whatever their order
  // (a pinwheel of four segments, each ending on the next, has no valid insertion order).
  // Each cell is cut by the pieces crossing its interior: on the local grid of the pieces'
  // positions and ends, fine cells not separated by a piece merge, and every merged region
  // must be a rectangle and every piece must separate two regions, or some segment ends
  // inside the cell.
  std::vector<RationalBox> out;
  for (const RationalBox& c : cells) {
    std::vector<size_t> cutting;
    std::vector<mpq_class> xs{c.x0, c.x1}, ys{c.y0, c.y1};
    for (size_t k = 0; k < segs.size(); ++k) {
      const AxisSegment& s = segs[k];
      const mpq_class &a0 = s.vertical ? c.x0 : c.y0, &a1 = s.vertical ? c.x1 : c.y1;
      const mpq_class &b0 = s.vertical ? c.y0 : c.x0, &b1 = s.vertical ? c.y1 : c.x1;
      const mpq_class lo = std::max(b0, s.from), hi = std::min(b1, s.to);
      if (!(a0 < s.position && s.position < a1 && hi > lo)) continue;
      cutting.push_back(k);
      auto& across = s.vertical ? xs : ys;
      auto& along = s.vertical ? ys : xs;
      across.push_back(s.position);
      along.push_back(lo);
      along.push_back(hi);
    }
    if (cutting.empty()) {
      out.push_back(c);
      continue;
    }
    for (auto* L : {&xs, &ys}) {
      std::sort(L->begin(), L->end());
      L->erase(std::unique(L->begin(), L->end()), L->end());
    }
    const size_t nx = xs.size() - 1, ny = ys.size() - 1;
    // Whether the fine edge on line `at` between `lo` and `hi` lies on a cutting piece.
    auto cut = [&](bool vertical, const mpq_class& at, const mpq_class& lo, const mpq_class& hi) {
      for (size_t k : cutting) {
        const AxisSegment& s = segs[k];
        if (s.vertical == vertical && s.position == at && s.from <= lo && hi <= s.to) return true;
      }
      return false;
    };
    std::vector<size_t> parent(nx * ny);
    for (size_t i = 0; i < parent.size(); ++i) parent[i] = i;
    auto find = [&](size_t i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    std::vector<std::pair<size_t, size_t>> separated;  // fine cells on the two sides of a piece
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        const size_t here = j * nx + i;
        if (i + 1 < nx) {
          if (cut(true, xs[i + 1], ys[j], ys[j + 1])) separated.push_back({here, here + 1});
          else parent[find(here)] = find(here + 1);
        }
        if (j + 1 < ny) {
          if (cut(false, ys[j + 1], xs[i], xs[i + 1])) separated.push_back({here, here + nx});
          else parent[find(here)] = find(here + nx);
        }
      }
    std::vector<RationalBox> region(nx * ny);
    std::vector<mpq_class> area(nx * ny);
    std::vector<bool> seen(nx * ny, false);
    std::vector<size_t> order;
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        const size_t r = find(j * nx + i);
        const RationalBox f{xs[i], ys[j], xs[i + 1], ys[j + 1]};
        if (!seen[r]) {
          seen[r] = true;
          region[r] = f;
          order.push_back(r);
        } else {
          RationalBox& b = region[r];
          b = {std::min(b.x0, f.x0), std::min(b.y0, f.y0), std::max(b.x1, f.x1), std::max(b.y1, f.y1)};
        }
        area[r] += (f.x1 - f.x0) * (f.y1 - f.y0);
      }
    // A piece with the same region on both sides is a slit; a region that is not a rectangle
    // wraps around an end. Either way some segment ends inside the cell.
    const bool slit = std::any_of(separated.begin(), separated.end(),
                                  [&](const auto& p) { return find(p.first) == find(p.second); });
    const bool rectangles = std::all_of(order.begin(), order.end(), [&](size_t r) {
      const RationalBox& b = region[r];
      return area[r] == (b.x1 - b.x0) * (b.y1 - b.y0);
    });
    if (slit || !rectangles) {
      // Name the first segment with an end inside the cell that no perpendicular piece crosses.
      auto dangles = [&](size_t k) {
        const AxisSegment& s = segs[k];
        const mpq_class& b0 = s.vertical ? c.y0 : c.x0;
        const mpq_class& b1 = s.vertical ? c.y1 : c.x1;
        for (const mpq_class& e : {s.from, s.to}) {
          if (!(b0 < e && e < b1)) continue;
          const bool crossed = std::any_of(cutting.begin(), cutting.end(), [&](size_t q) {
            return segs[q].vertical != s.vertical && segs[q].position == e && segs[q].from < s.position &&
                   s.position < segs[q].to;
          });
          if (!crossed) return true;
        }
        return false;
      };
      const auto culprit = std::find_if(cutting.begin(), cutting.end(), dangles);
      throw std::invalid_argument(name(culprit != cutting.end() ? *culprit : cutting.front()) + " ends inside cell " +
                                  box(c) + ": a segment must end on an edge of the mesh");
    }
    for (size_t r : order) out.push_back(region[r]);
  }
  return out;
}

}  // namespace knotwork
