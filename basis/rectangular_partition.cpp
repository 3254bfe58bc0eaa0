#include "basis/rectangular_partition.hpp"

#include <algorithm>
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
  for (size_t i = 0; i < cells_.size(); ++i)
    for (size_t j = i + 1; j < cells_.size(); ++j) {
      const RationalBox &a = cells_[i], &b = cells_[j];
      if (std::min(a.x1, b.x1) > std::max(a.x0, b.x0) && std::min(a.y1, b.y1) > std::max(a.y0, b.y0))
        throw std::invalid_argument("cells " + std::to_string(i) + " " + box(a) + " and " + std::to_string(j) + " " +
                                    box(b) + " overlap");
    }
  // No overlaps, so the union is the bounding rectangle exactly when the areas add up.
  if (area != (X1 - X0) * (Y1 - Y0))
    throw std::invalid_argument("the cells do not tile the rectangle [" + num(X0) + ", " + num(X1) + "] x [" +
                                num(Y0) + ", " + num(Y1) + "]: they leave a gap of area " +
                                num(mpq_class((X1 - X0) * (Y1 - Y0) - area)));
  for (int i = 0; i < num_cells(); ++i)
    for (int j = 0; j < num_cells(); ++j) {
      const RationalBox &a = cells_[i], &b = cells_[j];
      if (a.x1 == b.x0) {
        const mpq_class lo = std::max(a.y0, b.y0), hi = std::min(a.y1, b.y1);
        if (hi > lo) edges_.push_back({i, j, true, a.x1, lo, hi});
      }
      if (a.y1 == b.y0) {
        const mpq_class lo = std::max(a.x0, b.x0), hi = std::min(a.x1, b.x1);
        if (hi > lo) edges_.push_back({i, j, false, a.y1, lo, hi});
      }
    }
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

std::vector<RationalBox> insert_segments(std::vector<RationalBox> cells, const std::vector<AxisSegment>& segments) {
  for (size_t k = 0; k < segments.size(); ++k) {
    AxisSegment s = segments[k];
    for (mpq_class* v : {&s.position, &s.from, &s.to}) v->canonicalize();
    const std::string name = "segment " + std::to_string(k) + " (" + (s.vertical ? "x = " : "y = ") + num(s.position) +
                             " from " + num(s.from) + " to " + num(s.to) + ")";
    if (!(s.to > s.from)) throw std::invalid_argument(name + " has zero or negative length");
    std::vector<RationalBox> next;
    mpq_class covered = 0;  // length of the segment lying on cell interiors or edges
    for (const RationalBox& c : cells) {
      // In the segment's frame: `a` across, `b` along.
      const mpq_class &a0 = s.vertical ? c.x0 : c.y0, &a1 = s.vertical ? c.x1 : c.y1;
      const mpq_class &b0 = s.vertical ? c.y0 : c.x0, &b1 = s.vertical ? c.y1 : c.x1;
      const mpq_class lo = std::max(b0, s.from), hi = std::min(b1, s.to);
      if (a0 <= s.position && s.position <= a1 && hi > lo) {
        if (s.position == a0 || s.position == a1) {
          if (s.position == a0) covered += hi - lo;  // counted once, on the cell above/right
        } else {
          covered += hi - lo;
          if (lo > b0 || hi < b1)
            throw std::invalid_argument(name + " ends inside cell " + box(c) +
                                        ": a segment must end on an edge of the mesh");
          RationalBox first = c, second = c;
          (s.vertical ? first.x1 : first.y1) = s.position;
          (s.vertical ? second.x0 : second.y0) = s.position;
          next.push_back(first);
          next.push_back(second);
          continue;
        }
      }
      next.push_back(c);
    }
    if (covered != s.to - s.from)
      throw std::invalid_argument(name + " does not lie inside the rectangle of the mesh (or lies on its boundary)");
    cells = std::move(next);
  }
  return cells;
}

}  // namespace knotwork
