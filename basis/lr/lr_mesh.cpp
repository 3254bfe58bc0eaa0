#include "basis/lr/lr_mesh.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <numeric>
#include <span>
#include <stdexcept>

#include "basis/core/box_index.hpp"
#include "basis/core/bspline_kernel.hpp"
#include "basis/core/bspline_basis.hpp"

namespace knotwork {

size_t DyadicLrMesh::FunctionHash::operator()(const Function& f) const {
  uint64_t h = 1469598103934665603ull;
  for (const auto& t : f.knots)
    for (int64_t x : t) h = (h ^ uint64_t(x)) * 1099511628211ull;
  return h;
}

DyadicLrMesh::DyadicLrMesh(DyadicKnots u, DyadicKnots v) : knots_{std::move(u), std::move(v)} {
  for (int d = 0; d < 2; ++d) {
    p_[d] = knots_[d].degree();
    if (p_[d] > kMaxDegree) throw std::invalid_argument("LR B-splines: degree above " + std::to_string(kMaxDegree));
    if (knots_[d].base_elements() >= (1 << 20)) throw std::invalid_argument("LR B-splines: more than 2^20 elements");
    end_[d] = int64_t(knots_[d].base_elements()) << kGridLevel;
  }
  // The tensor B-splines: global knot vectors in grid coordinates, windows of degree+2.
  std::array<std::vector<int64_t>, 2> global;
  for (int d = 0; d < 2; ++d) {
    const int J = knots_[d].base_elements();
    for (int j = 0; j <= J; ++j) global[d].insert(global[d].end(), knots_[d].multiplicity(0, j), int64_t(j) << kGridLevel);
  }
  const int nu = static_cast<int>(global[0].size()) - p_[0] - 1, nv = static_cast<int>(global[1].size()) - p_[1] - 1;
  for (int a = 0; a < nu; ++a)
    for (int b = 0; b < nv; ++b) {
      Function f;
      for (int k = 0; k <= p_[0] + 1; ++k) f.knots[0][k] = global[0][a + k];
      for (int k = 0; k <= p_[1] + 1; ++k) f.knots[1][k] = global[1][b + k];
      functions_.emplace(f, 1.0);
    }
  for (int i = 0; i < knots_[0].base_elements(); ++i)
    for (int j = 0; j < knots_[1].base_elements(); ++j)
      elements_.push_back({{int64_t(i) << kGridLevel, int64_t(j) << kGridLevel},
                           {int64_t(i + 1) << kGridLevel, int64_t(j + 1) << kGridLevel}});
}

void DyadicLrMesh::add_line(const Segment& s) {
  auto& intervals = lines_[s.direction][s.at];
  intervals.push_back({s.from, s.to});
  std::sort(intervals.begin(), intervals.end());
  std::vector<std::pair<int64_t, int64_t>> merged;
  for (const auto& iv : intervals)
    if (!merged.empty() && iv.first <= merged.back().second) merged.back().second = std::max(merged.back().second, iv.second);
    else merged.push_back(iv);
  intervals = std::move(merged);
}

namespace {
// Whether one of a line's disjoint sorted pieces covers [from, to].
bool pieces_cover(const std::vector<std::pair<int64_t, int64_t>>& iv, int64_t from, int64_t to) {
  auto k = std::upper_bound(iv.begin(), iv.end(), std::pair<int64_t, int64_t>{from, INT64_MAX});
  if (k == iv.begin()) return false;
  --k;
  return k->first <= from && to <= k->second;
}
}  // namespace

bool DyadicLrMesh::covers(int direction, int64_t at, int64_t from, int64_t to) const {
  const auto it = lines_[direction].find(at);
  return it != lines_[direction].end() && pieces_cover(it->second, from, to);
}

namespace {

// Meshline pieces just added, per direction, by position. A box (a support or an element) that
// no older line cut can be cut now only where one of these pieces lies strictly inside it across
// its line and meets its extent along it (closed): a line that newly covers an extent meets it.
// Looking at every B-spline and element after every refinement was a quarter of an adaptive
// LR loop's refinement; looking at these only makes the same splits in the same order.
class AddedPieces {
 public:
  template <class Segments>
  explicit AddedPieces(const Segments& added) {
    for (const auto& s : added) by_direction_[s.direction].push_back({s.at, s.from, s.to});
    for (auto& v : by_direction_) std::sort(v.begin(), v.end());
  }
  // The first position lo < at < hi (increasing) of a piece in direction d where cut(at) holds,
  // or -1. The pieces' positions are the only ones where a line can cut a box made before they
  // came, or made since by splitting such a box at them (its extent along the line unchanged).
  template <class Cut>
  int64_t first_cut(int d, int64_t lo, int64_t hi, Cut cut) const {
    const auto& v = by_direction_[d];
    int64_t last = -1;
    for (auto it = std::upper_bound(v.begin(), v.end(), std::array<int64_t, 3>{lo, INT64_MAX, INT64_MAX});
         it != v.end() && (*it)[0] < hi; ++it)
      if ((*it)[0] != last && cut(last = (*it)[0])) return last;
    return -1;
  }
  // Whether a piece meets the box [lo[0], hi[0]] x [lo[1], hi[1]] as above, in either direction.
  bool meet_box(const std::array<int64_t, 2>& lo, const std::array<int64_t, 2>& hi) const {
    return meet(0, lo[0], hi[0], lo[1], hi[1]) || meet(1, lo[1], hi[1], lo[0], hi[0]);
  }

 private:
  // Whether a piece on a line of direction d lies at lo < at < hi and meets [from, to].
  bool meet(int d, int64_t lo, int64_t hi, int64_t from, int64_t to) const {
    const auto& v = by_direction_[d];
    for (auto it = std::upper_bound(v.begin(), v.end(), std::array<int64_t, 3>{lo, INT64_MAX, INT64_MAX});
         it != v.end() && (*it)[0] < hi; ++it)
      if ((*it)[1] <= to && from <= (*it)[2]) return true;
    return false;
  }

  std::array<std::vector<std::array<int64_t, 3>>, 2> by_direction_;  // (at, from, to)
};

// The first line position lo < at < hi (increasing) where the line covers [from, to] and
// usable(at) holds, or -1.
template <class Lines, class Usable>
int64_t first_line_cut(const Lines& lines, int64_t lo, int64_t hi, int64_t from, int64_t to, Usable usable) {
  for (auto it = lines.upper_bound(lo); it != lines.end() && it->first < hi; ++it)
    if (usable(it->first) && pieces_cover(it->second, from, to)) return it->first;
  return -1;
}

}  // namespace

// Knot insertion into one B-spline (bspline_kernel::split_weights), on the dyadic integers.
void DyadicLrMesh::split_functions(const std::vector<Segment>& added) {
  incidence_.reset();
  const AddedPieces pieces(added);
  // (B-spline, made here): one made here by a split is narrower across the split than the one
  // it came from, so an older line may cut it along the other direction: all lines are tried.
  std::vector<std::pair<Function, bool>> work;
  for (const auto& [f, w] : functions_) {
    const std::array<int64_t, 2> lo{f.knots[0][0], f.knots[1][0]}, hi{f.knots[0][p_[0] + 1], f.knots[1][p_[1] + 1]};
    if (pieces.meet_box(lo, hi)) work.push_back({f, false});
  }
  while (!work.empty()) {
    const Function f = work.back().first;
    const bool made_here = work.back().second;
    work.pop_back();
    const auto found = functions_.find(f);
    if (found == functions_.end()) continue;  // split since it was queued
    for (int d = 0; d < 2; ++d) {
      const int p = p_[d], o = 1 - d;
      const auto& t = f.knots[d];
      const int64_t lo = t[0], hi = t[p + 1], olo = f.knots[o][0], ohi = f.knots[o][p_[o] + 1];
      const auto not_a_knot = [&](int64_t at) { return std::find(t.begin(), t.begin() + p + 2, at) == t.begin() + p + 2; };
      const int64_t x = made_here ? first_line_cut(lines_[d], lo, hi, olo, ohi, not_a_knot)
                                  : pieces.first_cut(d, lo, hi, [&](int64_t at) { return not_a_knot(at) && covers(d, at, olo, ohi); });
      if (x < 0) continue;
      std::vector<double> T(p + 2);
      for (int k = 0; k <= p + 1; ++k) T[k] = parameter(d, t[k]);
      const auto [a, b] = bspline_kernel::split_weights<double>(T, parameter(d, x));
      const auto [left, right] = halves(f, d, x);
      const double weight = found->second;
      if (recording_) splits_.push_back({f, d, x, a, b});
      functions_.erase(found);
      functions_[left] += weight * a;
      functions_[right] += weight * b;
      work.push_back({left, true});
      work.push_back({right, true});
      break;
    }
  }
}

std::array<DyadicLrMesh::Function, 2> DyadicLrMesh::halves(const Function& f, int d, int64_t x) const {
  const int p = p_[d];
  const auto& t = f.knots[d];
  std::array<int64_t, kMaxDegree + 3> w{};
  const int at = static_cast<int>(std::upper_bound(t.begin(), t.begin() + p + 2, x) - t.begin());
  for (int k = 0; k <= p + 1; ++k) w[k < at ? k : k + 1] = t[k];
  w[at] = x;
  std::array<Function, 2> out{f, f};
  for (int k = 0; k <= p + 1; ++k) {
    out[0].knots[d][k] = w[k];
    out[1].knots[d][k] = w[k + 1];
  }
  return out;
}

void DyadicLrMesh::record_splits(bool on) {
  recording_ = on;
  splits_.clear();
}

Eigen::SparseMatrix<double> DyadicLrMesh::prolongation_from(const DyadicLrMesh& coarse) const {
  if (!recording_) throw std::logic_error("LR prolongation: the refinement's splits were not recorded");
  // Both meshes list their B-splines sorted by knots: one merge pairs the B-splines the
  // refinement kept (most of them), and only the split ones are expanded. Their splits are
  // found through the splits' hashes, sorted once (a hash map of the splits themselves cost as
  // much as building the refined mesh), their pieces by binary search.
  const auto less = [](const Function& a, const Function& b) { return a.knots < b.knots; };
  const Incidence& fine = incidence();
  const Incidence& rough = coarse.incidence();
  const FunctionHash hash;
  std::vector<std::pair<size_t, int>> by_hash(splits_.size());
  for (int k = 0; k < static_cast<int>(by_hash.size()); ++k) by_hash[k] = {hash(splits_[k].from), k};
  std::sort(by_hash.begin(), by_hash.end());
  const auto split_of = [&](const Function& f) -> const Split* {
    const size_t h = hash(f);
    for (auto it = std::lower_bound(by_hash.begin(), by_hash.end(), std::pair<size_t, int>{h, -1});
         it != by_hash.end() && it->first == h; ++it)
      if (splits_[it->second].from == f) return &splits_[it->second];
    return nullptr;
  };
  const auto fine_index = [&](const Function& f) {
    const auto it = std::lower_bound(fine.sorted.begin(), fine.sorted.end(), f, less);
    if (it == fine.sorted.end() || !(*it == f))
      throw std::logic_error("LR prolongation: a B-spline of the coarse mesh is neither split nor kept");
    return static_cast<int>(it - fine.sorted.begin());
  };
  const int nf = static_cast<int>(fine.sorted.size()), nc = static_cast<int>(rough.sorted.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(rough.sorted.size());
  std::vector<std::pair<Function, double>> work;
  int i = 0;
  for (int j = 0; j < nc; ++j) {
    const Function& g = rough.sorted[j];
    const double coarse_weight = rough.weights[j];
    while (i < nf && less(fine.sorted[i], g)) ++i;
    if (i < nf && fine.sorted[i] == g) {  // kept (its weight may have grown by pieces of others)
      entries.emplace_back(i, j, coarse_weight / fine.weights[i]);
      continue;
    }
    // (piece, its coefficient in the unweighted coarse B-spline), split as the refinement split it
    work.assign(1, {g, 1.0});
    while (!work.empty()) {
      const auto [f, c] = work.back();
      work.pop_back();
      if (const Split* split = split_of(f)) {
        const auto [left, right] = halves(split->from, split->direction, split->at);
        work.push_back({left, c * split->a});
        work.push_back({right, c * split->b});
        continue;
      }
      // coarse function = w_c B[coarse] = sum w_c c B[piece] = sum (w_c c / w_piece) (w_piece B[piece])
      const int k = fine_index(f);
      entries.emplace_back(k, j, coarse_weight * c / fine.weights[k]);
    }
  }
  Eigen::SparseMatrix<double> P(nf, nc);
  P.setFromTriplets(entries.begin(), entries.end());  // pieces reached twice are summed
  return P;
}

void DyadicLrMesh::split_elements(size_t first_inserted) {
  const AddedPieces pieces(std::span<const Segment>(inserted_).subspan(first_inserted));
  // (element, made here): as for the B-splines, a half may be cut by an older line.
  std::vector<std::pair<Element, bool>> work;
  std::vector<Element> done;
  for (const Element& e : elements_)
    if (pieces.meet_box(e.from, e.to)) work.push_back({e, false});
    else done.push_back(e);
  elements_.clear();
  while (!work.empty()) {
    const Element e = work.back().first;  // not a structured binding: clang 14 cannot capture one
    const bool made_here = work.back().second;
    work.pop_back();
    bool split = false;
    for (int d = 0; d < 2 && !split; ++d) {
      const int o = 1 - d;
      const int64_t x = made_here ? first_line_cut(lines_[d], e.from[d], e.to[d], e.from[o], e.to[o], [](int64_t) { return true; })
                                  : pieces.first_cut(d, e.from[d], e.to[d], [&](int64_t at) { return covers(d, at, e.from[o], e.to[o]); });
      if (x < 0) continue;
      Element a = e, b = e;
      a.to[d] = b.from[d] = x;
      work.push_back({a, true});
      work.push_back({b, true});
      split = true;
    }
    if (!split) done.push_back(e);
  }
  // Row by row, left to right: a stable order whatever the order of splitting.
  std::sort(done.begin(), done.end(), [](const Element& a, const Element& b) {
    return std::tie(a.from[1], a.from[0]) < std::tie(b.from[1], b.from[0]);
  });
  elements_ = std::move(done);
  incidence_.reset();
}

int DyadicLrMesh::refine(const std::vector<int>& marked, Strategy strategy) {
  const Incidence& inc = incidence();
  const std::vector<Function>& sorted = inc.sorted;
  const std::vector<std::vector<int>>& on = inc.on;
  std::vector<Segment> segments;
  auto midpoint = [&](int d, int64_t a, int64_t b) {
    if ((a + b) % 2 != 0)
      throw std::invalid_argument("an element of width " + std::to_string(parameter(d, b) - parameter(d, a)) +
                                  " cannot be halved on the LR grid (2^-40 of a level-0 element)");
    return (a + b) / 2;
  };
  std::vector<char> refine_function(sorted.size(), 0);
  for (int m : marked) {
    const Element& e = elements_.at(m);
    if (strategy == Strategy::kStructuredMesh) {
      for (int f : on[m]) refine_function[f] = 1;
      continue;
    }
    for (int d = 0; d < 2; ++d) {
      const int o = 1 - d;
      // Minimal span: the support shortest in parameter length across the line (grid units
      // are not lengths where level-0 elements differ in width).
      int64_t from = 0, to = 0;
      bool first = true;
      for (int f : on[m]) {
        const int64_t a = sorted[f].knots[o][0], b = sorted[f].knots[o][p_[o] + 1];
        if (first) from = a, to = b;
        else if (strategy == Strategy::kFullSpan) from = std::min(from, a), to = std::max(to, b);
        else if (parameter(o, b) - parameter(o, a) < parameter(o, to) - parameter(o, from)) from = a, to = b;
        first = false;
      }
      segments.push_back({d, midpoint(d, e.from[d], e.to[d]), from, to});
    }
  }
  for (size_t f = 0; f < sorted.size(); ++f)
    if (refine_function[f])
      for (int d = 0; d < 2; ++d) {
        const int o = 1 - d;
        const auto& t = sorted[f].knots[d];
        for (int k = 0; k <= p_[d]; ++k)
          if (t[k] < t[k + 1])
            segments.push_back({d, midpoint(d, t[k], t[k + 1]), sorted[f].knots[o][0], sorted[f].knots[o][p_[o] + 1]});
      }
  const size_t first_inserted = inserted_.size();
  for (const Segment& s : segments) add_line(s);
  inserted_.insert(inserted_.end(), segments.begin(), segments.end());
  split_functions(segments);
  const int before = extended_;
  keep_traces_independent();
  split_elements(first_inserted);
  return static_cast<int>(segments.size()) + extended_ - before;
}

void DyadicLrMesh::keep_traces_independent() {
  // The traces on the boundary must stay linearly independent (Dirichlet data are projected
  // onto them): a meshline that reaches a side is extended across every B-spline with a
  // trace there whose support it cuts without being one of its knots. Then every trace is a
  // B-spline of the side's own knot vector, and distinct ones are independent.
  for (;;) {
    std::vector<Segment> extensions = boundary_extensions();
    if (extensions.empty()) break;
    for (const Segment& s : extensions) add_line(s);
    inserted_.insert(inserted_.end(), extensions.begin(), extensions.end());
    extended_ += static_cast<int>(extensions.size());
    split_functions(extensions);
  }
}

int64_t DyadicLrMesh::grid(int d, double value) const {
  const DyadicKnots& K = knots_[d];
  const double a = K.breakpoint(0, 0), b = K.breakpoint(0, K.base_elements());
  if (!(value >= a && value <= b)) throw std::invalid_argument(std::to_string(value) + " is outside the parameter domain");
  int j = 0;
  while (j + 1 < K.base_elements() && value >= K.breakpoint(0, j + 1)) ++j;
  const double lo = K.breakpoint(0, j), hi = K.breakpoint(0, j + 1);
  const int64_t x = (int64_t(j) << kGridLevel) + std::llround((value - lo) / (hi - lo) * std::ldexp(1.0, kGridLevel));
  // A given meshline must sit at k / 2^m of a level-0 element with m <= 30 (up to the decimal
  // rounding of its input): refinement can reach it. Anything else would be moved silently.
  const bool coarse = (x & ((int64_t(1) << (kGridLevel - 30)) - 1)) == 0;
  if (!coarse || std::abs(parameter(d, x) - value) > 1e-12 * std::max(1.0, std::abs(value)))
    throw std::invalid_argument(std::to_string(value) + " is not a dyadic point k / 2^m (m <= 30) of a level-0 element");
  return x;
}

void DyadicLrMesh::insert(const std::vector<Segment>& segments, bool keep_traces) {
  const size_t first_inserted = inserted_.size();
  for (const Segment& s : segments) {
    const int d = s.direction, o = 1 - d;
    auto describe = [&] {
      return std::string(d == 0 ? "u = " : "v = ") + std::to_string(parameter(d, s.at)) + " from " +
             std::to_string(parameter(o, s.from)) + " to " + std::to_string(parameter(o, s.to));
    };
    if (!(0 < s.at && s.at < end_[d] && 0 <= s.from && s.from < s.to && s.to <= end_[o]))
      throw std::invalid_argument("the meshline " + describe() + " is empty or leaves the domain");
    const auto saved = lines_[d];
    add_line(s);
    bool traverses = false;
    for (const auto& [f, w] : functions_) {
      const auto& t = f.knots[d];
      if (t[0] < s.at && s.at < t[p_[d] + 1] && std::find(t.begin(), t.begin() + p_[d] + 2, s.at) == t.begin() + p_[d] + 2 &&
          covers(d, s.at, f.knots[o][0], f.knots[o][p_[o] + 1])) {
        traverses = true;
        break;
      }
    }
    if (!traverses) {
      lines_[d] = saved;
      throw std::invalid_argument("the meshline " + describe() +
                                  " traverses the support of no B-spline (the mesh would not be an LR mesh)");
    }
    inserted_.push_back(s);
    split_functions({s});
  }
  if (keep_traces) keep_traces_independent();
  split_elements(first_inserted);
}

std::vector<DyadicLrMesh::Segment> DyadicLrMesh::boundary_extensions() const {
  std::vector<Segment> out;
  for (const auto& [f, w] : functions_)
    for (int d = 0; d < 2; ++d) {  // lines u = x (d = 0) reach the sides v = 0 and v = end
      const int o = 1 - d, p = p_[d], q = p_[o];
      const auto& t = f.knots[d];
      const auto& s = f.knots[o];
      for (int side = 0; side < 2; ++side) {
        const bool touches = side == 0 ? s[q] == 0 : s[1] == end_[o];
        if (!touches) continue;
        const auto& lines = lines_[d];
        for (auto it = lines.upper_bound(t[0]); it != lines.end() && it->first < t[p + 1]; ++it) {
          const int64_t x = it->first;
          if (std::find(t.begin(), t.begin() + p + 2, x) != t.begin() + p + 2) continue;
          const bool reaches = side == 0 ? it->second.front().first == 0 : it->second.back().second == end_[o];
          if (!reaches) continue;
          out.push_back(side == 0 ? Segment{d, x, 0, s[q + 1]} : Segment{d, x, s[0], end_[o]});
        }
      }
    }
  return out;
}

const DyadicLrMesh::Incidence& DyadicLrMesh::incidence() const {
  if (incidence_) return *incidence_;
  auto result = std::make_shared<Incidence>();
  std::vector<Function>& sorted = result->sorted;
  std::vector<std::pair<const Function*, double>> listed;
  listed.reserve(functions_.size());
  for (const auto& [f, w] : functions_) listed.push_back({&f, w});
  std::sort(listed.begin(), listed.end(), [](const auto& a, const auto& b) { return a.first->knots < b.first->knots; });
  sorted.reserve(listed.size());
  result->weights.reserve(listed.size());
  for (const auto& [f, w] : listed) {
    sorted.push_back(*f);
    result->weights.push_back(w);
  }
  // The elements in the one R-tree (integer boxes), queried with every support: the elements
  // inside it, each element's list in the functions' sorted order.
  const int n = static_cast<int>(elements_.size());
  using ElementIndex = BoxIndex<int64_t, int>;
  std::vector<ElementIndex::Entry> entries;
  entries.reserve(n);
  for (int e = 0; e < n; ++e)
    entries.emplace_back(ElementIndex::box(elements_[e].from[0], elements_[e].from[1], elements_[e].to[0], elements_[e].to[1]), e);
  const ElementIndex index(entries);
  entries = {};
  std::vector<std::vector<int>>& on = result->on;
  on.assign(n, {});
  std::vector<int> inside;
  for (int f = 0; f < static_cast<int>(sorted.size()); ++f) {
    index.covered_by(ElementIndex::box(sorted[f].knots[0][0], sorted[f].knots[1][0], sorted[f].knots[0][p_[0] + 1],
                                       sorted[f].knots[1][p_[1] + 1]),
                     inside);
    for (int e : inside) on[e].push_back(f);
  }
  incidence_ = result;
  return *incidence_;
}

BezierMesh DyadicLrMesh::bezier_mesh() const {
  const Incidence& inc = incidence();
  const int p = p_[0], q = p_[1];
  // A B-spline's Bernstein coefficients on an element depend only on its knots in one
  // direction and the element's interval there: most pairs repeat, so each is computed once.
  struct Key {
    std::array<int64_t, kMaxDegree + 4> k;
    bool operator==(const Key& o) const { return k == o.k; }
  };
  struct KeyHash {
    size_t operator()(const Key& key) const {
      uint64_t h = 1469598103934665603ull;
      for (int64_t x : key.k) h = (h ^ uint64_t(x)) * 1099511628211ull;
      return h;
    }
  };
  std::array<std::unordered_map<Key, Eigen::VectorXd, KeyHash>, 2> seen;
  auto bernstein = [&](const Function& f, int d, int64_t a, int64_t b) -> const Eigen::VectorXd& {
    Key key{};
    for (int i = 0; i <= p_[d] + 1; ++i) key.k[i] = f.knots[d][i];
    key.k[kMaxDegree + 2] = a;
    key.k[kMaxDegree + 3] = b;
    auto [it, fresh] = seen[d].try_emplace(key);
    if (fresh) {
      std::vector<double> t(p_[d] + 2);
      for (int i = 0; i <= p_[d] + 1; ++i) t[i] = parameter(d, f.knots[d][i]);
      it->second = single_bspline_bernstein(t, parameter(d, a), parameter(d, b));
    }
    return it->second;
  };
  const std::vector<double>& weight = inc.weights;
  BezierMesh mesh;
  mesh.set_num_functions(static_cast<int>(inc.sorted.size()));
  mesh.set_boundary_names({"bottom", "right", "top", "left"});
  for (size_t c = 0; c < elements_.size(); ++c) {
    const Element& e = elements_[c];
    BezierCell cell;
    cell.u0 = parameter(0, e.from[0]);
    cell.u1 = parameter(0, e.to[0]);
    cell.v0 = parameter(1, e.from[1]);
    cell.v1 = parameter(1, e.to[1]);
    cell.degree_u = p;
    cell.degree_v = q;
    if (e.from[1] == 0) cell.boundary[kSideBottom] = 0;
    if (e.to[0] == end_[0]) cell.boundary[kSideRight] = 1;
    if (e.to[1] == end_[1]) cell.boundary[kSideTop] = 2;
    if (e.from[0] == 0) cell.boundary[kSideLeft] = 3;
    const std::vector<int>& ids = inc.on[c];
    Eigen::MatrixXd C(static_cast<int>(ids.size()), (p + 1) * (q + 1));
    for (size_t k = 0; k < ids.size(); ++k) {
      const Function& f = inc.sorted[ids[k]];
      const Eigen::VectorXd& bu = bernstein(f, 0, e.from[0], e.to[0]);
      const Eigen::VectorXd& bv = bernstein(f, 1, e.from[1], e.to[1]);
      for (int b = 0; b <= q; ++b)
        for (int a = 0; a <= p; ++a) C(static_cast<int>(k), a + (p + 1) * b) = weight[ids[k]] * bu[a] * bv[b];
    }
    mesh.add_cell(cell, ids, mesh.add_extraction(std::move(C)));
  }
  return mesh;
}

DyadicLrMesh::Dependence DyadicLrMesh::dependence(const BezierMesh& mesh, int max_checked) {
  const int nf = mesh.num_functions();
  const size_t full = mesh.num_cells() ? size_t(mesh.cell(0).degree_u + 1) * (mesh.cell(0).degree_v + 1) : 1;
  std::vector<char> has_free_element(nf, 0);
  for (int c = 0; c < mesh.num_cells(); ++c)
    if (mesh.functions(c).size() <= full)
      for (int f : mesh.functions(c)) has_free_element[f] = 1;
  std::vector<int> row(nf, -1);  // candidate index of an overloaded function
  std::vector<int> candidates;
  for (int f = 0; f < nf; ++f)
    if (!has_free_element[f]) {
      row[f] = static_cast<int>(candidates.size());
      candidates.push_back(f);
    }
  Dependence out;
  out.overloaded = static_cast<int>(candidates.size());
  out.dependent = 0;
  if (candidates.empty()) return out;
  // Candidates that share no element have disjoint Bézier columns: the rank is the sum of
  // the ranks of the groups connected through shared elements (small clusters in practice).
  std::vector<int> parent(candidates.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int c = 0; c < mesh.num_cells(); ++c) {
    int first = -1;
    for (int f : mesh.functions(c))
      if (row[f] >= 0) {
        if (first < 0) first = root(row[f]);
        else parent[root(row[f])] = first;
      }
  }
  // Each group's candidates (their position in the group) and cells, in one pass each.
  std::map<int, std::pair<std::vector<int>, std::vector<int>>> groups;  // root -> (candidates, cells)
  std::vector<int> column(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    auto& members = groups[root(static_cast<int>(k))].first;
    column[k] = static_cast<int>(members.size());
    members.push_back(static_cast<int>(k));
  }
  for (int c = 0; c < mesh.num_cells(); ++c) {
    std::vector<int> roots;
    for (int f : mesh.functions(c))
      if (row[f] >= 0) roots.push_back(root(row[f]));
    std::sort(roots.begin(), roots.end());
    roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
    for (int r : roots) groups[r].second.push_back(c);
  }
  for (const auto& [r, group] : groups) {
    const auto& [members, cells] = group;
    if (static_cast<int>(members.size()) > max_checked) {
      out.dependent = -1;
      return out;
    }
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(cells.size() * full),
                                              static_cast<Eigen::Index>(members.size()));
    for (size_t k = 0; k < cells.size(); ++k) {
      const auto ids = mesh.functions(cells[k]);
      for (size_t i = 0; i < ids.size(); ++i)
        if (row[ids[i]] >= 0 && root(row[ids[i]]) == r)
          A.block(static_cast<Eigen::Index>(k * full), column[row[ids[i]]], full, 1) =
              mesh.extraction(cells[k]).row(static_cast<Eigen::Index>(i)).transpose();
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    qr.setThreshold(1e-10);
    const int nullity = static_cast<int>(members.size()) - static_cast<int>(qr.rank());
    if (nullity > 0 && out.element < 0) {
      // The first column the pivoting left out is a combination of the ones before it: its
      // function takes part in a relation; report a cell of its support.
      const int f = candidates[members[qr.colsPermutation().indices()[qr.rank()]]];
      for (int c : cells)
        if (const auto ids = mesh.functions(c); std::find(ids.begin(), ids.end(), f) != ids.end()) {
          out.element = c;
          break;
        }
    }
    out.dependent += nullity;
  }
  return out;
}

}  // namespace knotwork
