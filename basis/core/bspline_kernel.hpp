#pragma once
// The B-spline kernel, written once for every number type knotwork computes in: double on the
// quadrature-point path, GMP rationals (mpq_class) where dimensions, independence and
// refinement are certified exactly. Evaluation by the Cox–de Boor recurrence, and knot
// insertion (Boehm) as it acts on one B-spline. Before, the same recurrences were written in
// four places (the tensor basis, the LR mesh on a T-mesh, the dyadic LR mesh, the PT-splines);
// now those call these templates with their own number type.
//
// Include it only where it is used (it is a template header); BSplineBasis1D
// (bspline_basis.hpp) is the double-precision interface most code wants.
#include <algorithm>
#include <map>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

namespace knotwork::bspline_kernel {

// Values of the p+1 B-splines alive on span s of `knots` (knots[s] <= x < knots[s+1], with p
// knots before s and after s+1): out[j] is function s-p+j. Cox–de Boor in the triangular
// form (Piegl & Tiller, A2.2).
template <class Number>
void alive_on_span(const Number* knots, int s, int p, const Number& x, Number* out) {
  std::vector<Number> left(p + 1), right(p + 1);
  out[0] = Number(1);
  for (int j = 1; j <= p; ++j) {
    left[j] = x - knots[s + 1 - j];
    right[j] = knots[s + j] - x;
    Number saved(0);
    for (int r = 0; r < j; ++r) {
      const Number temp = out[r] / (right[r + 1] + left[j - r]);
      out[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    out[j] = saved;
  }
}

// Values at x of every B-spline of degree p on the knot vector t (t.size() - p - 1 of them),
// by the recurrence over degrees; no padding needed. x at t.back() belongs to the last
// non-empty interval (the closed right end of a domain).
template <class Number>
std::vector<Number> all_at(std::span<const Number> t, int p, const Number& x) {
  std::vector<Number> N(t.size() - 1, Number(0));
  for (std::size_t i = 0; i + 1 < t.size(); ++i)
    if ((t[i] <= x && x < t[i + 1]) || (x == t.back() && t[i] < x && t[i + 1] == x)) N[i] = 1;
  for (int q = 1; q <= p; ++q)
    for (std::size_t i = 0; i + q + 1 < t.size(); ++i) {
      Number v(0);
      if (t[i + q] != t[i]) v += (x - t[i]) / (t[i + q] - t[i]) * N[i];
      if (t[i + q + 1] != t[i + 1]) v += (t[i + q + 1] - x) / (t[i + q + 1] - t[i + 1]) * N[i + 1];
      N[i] = v;
    }
  N.resize(t.size() - p - 1);
  return N;
}

// The B-spline with local knots t (degree t.size() - 2) at x; 0 outside [t.front(), t.back()).
template <class Number>
Number local_value(std::span<const Number> t, const Number& x) {
  if (x < t.front() || !(x < t.back())) return Number(0);
  return all_at(t, static_cast<int>(t.size()) - 2, x)[0];
}

// Knot insertion into one B-spline: with w = t and x inserted (t.front() < x < t.back()),
//   B[t] = a B[w_0 .. w_{p+1}] + b B[w_1 .. w_{p+2}]   (p = t.size() - 2).
// Returns {a, b}. Boehm's algorithm is this, applied to every B-spline a knot meets.
template <class Number>
std::pair<Number, Number> split_weights(std::span<const Number> t, const Number& x) {
  const int p = static_cast<int>(t.size()) - 2;
  const Number a = x >= t[p] ? Number(1) : Number((x - t[0]) / (t[p] - t[0]));
  const Number b = x <= t[1] ? Number(1) : Number((t[p + 1] - x) / (t[p + 1] - t[1]));
  return {a, b};
}

// The B-spline with local knots t written in the B-splines of the finer knot vector `fine`
// (which holds every knot of t at least as often): pairs (index of the first knot of the
// window of `fine` that is the piece's knot vector, coefficient), by repeated split_weights.
// Throws std::invalid_argument if `fine` lacks a knot of t.
template <class Number>
std::vector<std::pair<int, Number>> in_finer_knots(const std::vector<Number>& t, const std::vector<Number>& fine) {
  auto count = [](const std::vector<Number>& v, const Number& x) {
    const auto r = std::equal_range(v.begin(), v.end(), x);
    return static_cast<long>(r.second - r.first);
  };
  for (const Number& x : t)
    if (count(t, x) > count(fine, x)) throw std::invalid_argument("in_finer_knots: the knots are not in the fine vector");
  // Insert, one at a time, the knots of `fine` strictly inside the support that a piece lacks:
  // then each piece has every knot of `fine` inside its support, so it is a window of `fine`.
  std::map<std::vector<Number>, Number> done;
  std::vector<std::pair<std::vector<Number>, Number>> work{{t, Number(1)}};
  while (!work.empty()) {
    auto piece = std::move(work.back());
    work.pop_back();
    const std::vector<Number>& k = piece.first;
    const auto lo = std::upper_bound(fine.begin(), fine.end(), k.front());
    const auto hi = std::lower_bound(fine.begin(), fine.end(), k.back());
    auto missing = lo;
    while (missing != hi && count(k, *missing) >= count(fine, *missing)) ++missing;
    if (missing == hi) {
      done[k] += piece.second;
      continue;
    }
    std::vector<Number> w = k;
    w.insert(std::upper_bound(w.begin(), w.end(), *missing), *missing);
    const auto [a, b] = split_weights<Number>(k, *missing);
    work.push_back({{w.begin(), w.end() - 1}, piece.second * a});
    work.push_back({{w.begin() + 1, w.end()}, piece.second * b});
  }
  std::vector<std::pair<int, Number>> out;
  for (const auto& [k, c] : done) {
    if (c == 0) continue;
    // The window starts at the last copies of k's first knot in `fine`.
    const auto first = std::lower_bound(fine.begin(), fine.end(), k.front());
    out.emplace_back(static_cast<int>(first - fine.begin() + count(fine, k.front()) - count(k, k.front())), c);
  }
  return out;
}

}  // namespace knotwork::bspline_kernel
