#include "basis/tmesh/lr_spline.hpp"

#include "basis/core/box_index.hpp"
#include "basis/core/bspline_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace knotwork {

namespace {


// v as a fraction of the rectangle's side spanned by `lines` (its first and last coordinate).
// Doubles suffice for the index: it only narrows the search, the exact test follows, and every
// box is widened far beyond the rounding of get_d.
double unit(const mpq_class& v, const std::vector<mpq_class>& lines) {
  const double a = lines.front().get_d();
  return (v.get_d() - a) / (lines.back().get_d() - a);
}
constexpr double kWiden = 1e-9;

}  // namespace

struct LrMesh::SupportIndex {
  BoxIndex<double, Knots> tree;
};

namespace {
BoxIndex<double, LrMesh::Knots>::Box support_box(const LrMesh::Knots& k, const std::vector<mpq_class>& xs,
                                                 const std::vector<mpq_class>& ys) {
  return BoxIndex<double, LrMesh::Knots>::box(unit(k.first.front(), xs) - kWiden, unit(k.second.front(), ys) - kWiden,
                                              unit(k.first.back(), xs) + kWiden, unit(k.second.back(), ys) + kWiden);
}
}  // namespace

LrMesh::SupportIndex& LrMesh::index() const {
  if (!index_.value) {
    std::vector<BoxIndex<double, Knots>::Entry> entries;
    entries.reserve(splines_.size());
    for (const auto& [k, w] : splines_) entries.emplace_back(support_box(k, xs_, ys_), k);
    index_.value = std::make_shared<SupportIndex>(SupportIndex{BoxIndex<double, Knots>(entries)});
  }
  return *index_.value;
}

void LrMesh::index_add(const Knots& k) {
  if (index_.value) index_.value->tree.insert(support_box(k, xs_, ys_), k);
}

void LrMesh::index_remove(const Knots& k) {
  if (index_.value) index_.value->tree.remove(support_box(k, xs_, ys_), k);
}

LrMesh::LrMesh(const std::vector<mpq_class>& xs, const std::vector<mpq_class>& ys, int m, int n, const C0Lines& c0)
    : m_(m), n_(n), xs_(xs), ys_(ys) {
  if (m < 1 || n < 1) throw std::invalid_argument("LR B-splines need degree >= 1");
  grid_cells(xs, ys);  // validates the coordinates
  for (size_t i = 1; i + 1 < xs.size(); ++i) lines_[1][xs[i]].push_back({ys.front(), ys.back()});
  for (size_t j = 1; j + 1 < ys.size(); ++j) lines_[0][ys[j]].push_back({xs.front(), xs.back()});
  auto knots = [](const std::vector<mpq_class>& L, const std::vector<mpq_class>& lines, int p) {
    std::vector<mpq_class> interior;
    for (size_t i = 1; i + 1 < L.size(); ++i)
      interior.insert(interior.end(), std::find(lines.begin(), lines.end(), L[i]) != lines.end() ? p : 1, L[i]);
    for (const mpq_class& v : lines)
      if (std::find(L.begin() + 1, L.end() - 1, v) == L.end() - 1)
        throw std::invalid_argument("LR mesh: the C0 line at " + v.get_str() + " is not an interior line");
    return open_knot_vector(interior, L.front(), L.back(), p);
  };
  const std::vector<mpq_class> kx = knots(xs, c0.x, m), ky = knots(ys, c0.y, n);
  for (size_t j = 0; j + n + 1 < ky.size(); ++j)
    for (size_t i = 0; i + m + 1 < kx.size(); ++i)
      splines_[{{kx.begin() + i, kx.begin() + i + m + 2}, {ky.begin() + j, ky.begin() + j + n + 2}}] = 1;
}

const std::vector<LrBSpline>& LrMesh::splines() const {
  const std::lock_guard<std::mutex> guard(*listed_lock_);
  if (listed_stale_) {
    listed_.clear();
    for (const auto& [k, w] : splines_) listed_.push_back({k.first, k.second, w});
    listed_stale_ = false;
  }
  return listed_;
}

bool LrMesh::has_line_through(bool vertical, const mpq_class& at, const mpq_class& along) const {
  const auto& across = vertical ? xs_ : ys_;
  if (at == across.front() || at == across.back()) return true;
  const auto it = lines_[vertical].find(at);
  if (it == lines_[vertical].end()) return false;
  for (const auto& [a, b] : it->second)
    if (a <= along && along <= b) return true;
  return false;
}

bool LrMesh::traverses(bool vertical, const mpq_class& at, const mpq_class& from, const mpq_class& to) const {
  const auto it = lines_[vertical].find(at);
  if (it == lines_[vertical].end()) return false;
  for (const auto& [a, b] : it->second)
    if (a <= from && to <= b) return true;
  return false;
}

void LrMesh::insert(const AxisSegment& segment) {
  if (!try_insert(segment))
    throw std::invalid_argument("LR meshline " + std::string(segment.vertical ? "x = " : "y = ") +
                                mpq_class(segment.position).get_str() + " from " + mpq_class(segment.from).get_str() +
                                " to " + mpq_class(segment.to).get_str() +
                                " traverses the support of no B-spline: not an LR refinement");
}

bool LrMesh::try_insert(const AxisSegment& segment) {
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
  // The B-splines the meshline splits: supports that meet it, found through the index (in
  // the order of splines_, as the scan of every B-spline this replaced found them). A split
  // support meets the new piece itself: one covered by the line as it was has its knot.
  std::vector<Knots> split;
  // The meshline as a (degenerate, widened) box in the rectangle's unit coordinates.
  const double u0 = unit(s.vertical ? s.position : s.from, xs_), u1 = unit(s.vertical ? s.position : s.to, xs_);
  const double v0 = unit(s.vertical ? s.from : s.position, ys_), v1 = unit(s.vertical ? s.to : s.position, ys_);
  std::vector<Knots> near;
  index().tree.intersecting(BoxIndex<double, Knots>::box(u0 - kWiden, v0 - kWiden, u1 + kWiden, v1 + kWiden), near);
  for (const Knots& k : near) {
    const auto& t = s.vertical ? k.first : k.second;
    const auto& o = s.vertical ? k.second : k.first;
    if (t.front() < s.position && s.position < t.back() && std::find(t.begin(), t.end(), s.position) == t.end() &&
        covers(o.front(), o.back()))
      split.push_back(k);
  }
  if (split.empty()) return false;
  std::sort(split.begin(), split.end());
  lines_[s.vertical][s.position] = std::move(merged);
  inserted_.push_back(s);
  refine(std::move(split));
  return true;
}

void LrMesh::refine(std::vector<Knots> work) {
  listed_stale_ = true;
  while (!work.empty()) {
    const Knots k = std::move(work.back());
    work.pop_back();
    const auto found = splines_.find(k);
    if (found == splines_.end()) continue;  // already split
    for (int vertical = 1; vertical >= 0; --vertical) {
      const auto& t = vertical ? k.first : k.second;
      const auto& o = vertical ? k.second : k.first;
      const auto& lines = lines_[vertical];
      const auto first = lines.upper_bound(t.front()), last = lines.lower_bound(t.back());
      const auto line = std::find_if(first, last, [&](const auto& l) {
        return std::find(t.begin(), t.end(), l.first) == t.end() && traverses(vertical, l.first, o.front(), o.back());
      });
      if (line == last) continue;
      std::vector<mpq_class> w = t;
      w.insert(std::upper_bound(w.begin(), w.end(), line->first), line->first);
      const auto [a, c] = bspline_kernel::split_weights<mpq_class>(t, line->first);
      const std::vector<mpq_class> left(w.begin(), w.end() - 1), right(w.begin() + 1, w.end());
      const mpq_class weight = found->second;
      index_remove(found->first);
      splines_.erase(found);
      const Knots kl = vertical ? Knots{left, k.second} : Knots{k.first, left};
      const Knots kr = vertical ? Knots{right, k.second} : Knots{k.first, right};
      for (const auto& [piece, share] : {std::pair<const Knots*, mpq_class>{&kl, weight * a}, std::pair<const Knots*, mpq_class>{&kr, weight * c}}) {
        const auto [at, added] = splines_.try_emplace(*piece, 0);
        at->second += share;
        if (added) index_add(*piece);
      }
      work.push_back(kl);
      work.push_back(kr);
      break;
    }
  }
}

std::vector<std::pair<int, mpq_class>> refine_bspline(const std::vector<mpq_class>& t,
                                                      const std::vector<mpq_class>& fine) {
  return bspline_kernel::in_finer_knots(t, fine);
}

std::vector<RationalBox> LrMesh::cells() const { return insert_segments(grid_cells(xs_, ys_), inserted_); }

}  // namespace knotwork
