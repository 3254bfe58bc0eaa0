#include "basis/lr_spline.hpp"

#include <algorithm>
#include <stdexcept>

namespace knotwork {

namespace {

std::vector<mpq_class> open_knots(const std::vector<mpq_class>& coordinates, int degree) {
  return open_knot_vector({coordinates.begin() + 1, coordinates.end() - 1}, coordinates.front(), coordinates.back(),
                          degree);
}

// B[t] = a B[first p+2 knots of t + c] + b B[last p+2] (knot insertion into one B-spline).
std::pair<mpq_class, mpq_class> split_weights(const std::vector<mpq_class>& t, const mpq_class& c) {
  const int p = static_cast<int>(t.size()) - 2;
  const mpq_class a = c >= t[p] ? mpq_class(1) : mpq_class((c - t[0]) / (t[p] - t[0]));
  const mpq_class b = c <= t[1] ? mpq_class(1) : mpq_class((t[p + 1] - c) / (t[p + 1] - t[1]));
  return {a, b};
}

}  // namespace

LrMesh::LrMesh(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys, int m, int n)
    : m_(m), n_(n), xs_(xs), ys_(ys) {
  if (m < 1 || n < 1) throw std::invalid_argument("LR B-splines need degree >= 1");
  grid_cells(xs, ys);  // validates the coordinates
  for (size_t i = 1; i + 1 < xs.size(); ++i) lines_[1][xs[i]].push_back({ys.front(), ys.back()});
  for (size_t j = 1; j + 1 < ys.size(); ++j) lines_[0][ys[j]].push_back({xs.front(), xs.back()});
  const std::vector<mpq_class> kx = open_knots(xs, m), ky = open_knots(ys, n);
  for (size_t j = 0; j + n + 1 < ky.size(); ++j)
    for (size_t i = 0; i + m + 1 < kx.size(); ++i)
      splines_.push_back({{kx.begin() + i, kx.begin() + i + m + 2}, {ky.begin() + j, ky.begin() + j + n + 2}, 1});
}

bool LrMesh::traverses(bool vertical, const mpq_class& at, const mpq_class& from, const mpq_class& to) const {
  const auto it = lines_[vertical].find(at);
  if (it == lines_[vertical].end()) return false;
  for (const auto& [a, b] : it->second)
    if (a <= from && to <= b) return true;
  return false;
}

void LrMesh::insert(const AxisSegment& segment) {
  AxisSegment s = segment;
  for (mpq_class* v : {&s.position, &s.from, &s.to}) v->canonicalize();
  const auto& across = s.vertical ? xs_ : ys_;
  const auto& along = s.vertical ? ys_ : xs_;
  if (!(s.to > s.from) || !(across.front() < s.position && s.position < across.back()) || s.from < along.front() ||
      s.to > along.back())
    throw std::invalid_argument("LR meshline " + s.position.get_str() + " from " + s.from.get_str() + " to " +
                                s.to.get_str() + " is empty or leaves the rectangle");
  // The merged meshline, checked before the mesh changes (a refused insertion leaves it as it was).
  const auto existing = lines_[s.vertical].find(s.position);
  std::vector<std::pair<mpq_class, mpq_class>> intervals;
  if (existing != lines_[s.vertical].end()) intervals = existing->second;
  intervals.push_back({s.from, s.to});
  std::sort(intervals.begin(), intervals.end());
  std::vector<std::pair<mpq_class, mpq_class>> merged;
  for (const auto& iv : intervals)
    if (!merged.empty() && iv.first <= merged.back().second) merged.back().second = std::max(merged.back().second, iv.second);
    else merged.push_back(iv);
  auto covers = [&](const mpq_class& from, const mpq_class& to) {
    return std::any_of(merged.begin(), merged.end(), [&](const auto& iv) { return iv.first <= from && to <= iv.second; });
  };
  const bool splits_one = std::any_of(splines_.begin(), splines_.end(), [&](const LrBSpline& b) {
    const auto& t = s.vertical ? b.x : b.y;
    const auto& o = s.vertical ? b.y : b.x;
    return t.front() < s.position && s.position < t.back() && std::find(t.begin(), t.end(), s.position) == t.end() &&
           covers(o.front(), o.back());
  });
  if (!splits_one)
    throw std::invalid_argument("LR meshline " + std::string(s.vertical ? "x = " : "y = ") + s.position.get_str() +
                                " from " + s.from.get_str() + " to " + s.to.get_str() +
                                " traverses the support of no B-spline: not an LR refinement");
  lines_[s.vertical][s.position] = std::move(merged);
  inserted_.push_back(s);
  refine();
}

void LrMesh::refine() {
  for (bool changed = true; changed;) {
    changed = false;
    std::map<std::pair<std::vector<mpq_class>, std::vector<mpq_class>>, mpq_class> next;
    for (const LrBSpline& b : splines_) {
      bool split = false;
      for (int vertical = 1; vertical >= 0 && !split; --vertical) {
        const auto& t = vertical ? b.x : b.y;
        const auto& o = vertical ? b.y : b.x;
        for (const auto& [at, intervals] : lines_[vertical]) {
          if (!(t.front() < at && at < t.back()) || std::find(t.begin(), t.end(), at) != t.end()) continue;
          if (!traverses(vertical, at, o.front(), o.back())) continue;
          std::vector<mpq_class> w = t;
          w.insert(std::upper_bound(w.begin(), w.end(), at), at);
          const auto [a, c] = split_weights(t, at);
          std::vector<mpq_class> left(w.begin(), w.end() - 1), right(w.begin() + 1, w.end());
          if (vertical) {
            next[{left, b.y}] += b.weight * a;
            next[{right, b.y}] += b.weight * c;
          } else {
            next[{b.x, left}] += b.weight * a;
            next[{b.x, right}] += b.weight * c;
          }
          split = changed = true;
          break;
        }
      }
      if (!split) next[{b.x, b.y}] += b.weight;
    }
    splines_.clear();
    for (auto& [knots, weight] : next) splines_.push_back({knots.first, knots.second, weight});
  }
}

std::vector<RationalBox> LrMesh::cells() const { return insert_segments(grid_cells(xs_, ys_), inserted_); }

}  // namespace knotwork
