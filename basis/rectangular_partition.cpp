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
