#include "basis/core/bspline_basis.hpp"

#include "basis/core/bspline_kernel.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "basis/core/bezier_ops.hpp"

namespace knotwork {

namespace {
[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }
std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

BSplineBasis1D::BSplineBasis1D(int degree, std::vector<double> knots)
    : p_(degree), knots_(std::move(knots)) {
  if (p_ < 0) fail("degree must be >= 0, got " + std::to_string(p_));
  for (size_t i = 0; i < knots_.size(); ++i)
    if (!std::isfinite(knots_[i])) fail("knot " + std::to_string(i) + " is not a finite number");
  if (static_cast<int>(knots_.size()) < 2 * p_ + 2)
    fail("a degree-" + std::to_string(p_) + " knot vector needs at least " +
         std::to_string(2 * p_ + 2) + " knots, got " + std::to_string(knots_.size()));
  for (size_t i = 1; i < knots_.size(); ++i)
    if (knots_[i] < knots_[i - 1])
      fail("knot vector is not non-decreasing at position " + std::to_string(i) + " (" +
           num(knots_[i - 1]) + " > " + num(knots_[i]) + ")");
  for (size_t i = 0; i < knots_.size();) {
    size_t j = i;
    while (j < knots_.size() && knots_[j] == knots_[i]) ++j;
    if (static_cast<int>(j - i) > p_ + 1)
      fail("knot " + num(knots_[i]) + " has multiplicity " + std::to_string(j - i) +
           ", more than degree+1 = " + std::to_string(p_ + 1));
    i = j;
  }
  if (!(domain_end() > domain_begin())) fail("knot vector spans an empty domain");
}

BSplineBasis1D BSplineBasis1D::open_uniform(int degree, double a, double b, int elements,
                                            int multiplicity) {
  std::vector<double> k(degree + 1, a);
  for (int e = 1; e < elements; ++e)
    for (int m = 0; m < multiplicity; ++m) k.push_back(a + (b - a) * e / elements);
  k.insert(k.end(), degree + 1, b);
  return BSplineBasis1D(degree, std::move(k));
}

bool BSplineBasis1D::is_open() const {
  const int n = static_cast<int>(knots_.size());
  for (int i = 0; i <= p_; ++i)
    if (knots_[i] != knots_[0] || knots_[n - 1 - i] != knots_[n - 1]) return false;
  return true;
}

int BSplineBasis1D::find_span(double t) const {
  const int n = num_functions();
  if (t >= knots_[n]) {
    int s = n - 1;
    while (s > p_ && knots_[s] == knots_[s + 1]) --s;
    return s;
  }
  if (t <= knots_[p_]) {
    int s = p_;
    while (s < n - 1 && knots_[s] == knots_[s + 1]) ++s;
    return s;
  }
  auto it = std::upper_bound(knots_.begin() + p_, knots_.begin() + n + 1, t);
  return static_cast<int>(it - knots_.begin()) - 1;
}

void BSplineBasis1D::evaluate(int s, double t, double* N) const {
  bspline_kernel::alive_on_span<double>(knots_.data(), s, p_, t, N);
}

void BSplineBasis1D::evaluate_derivatives(int s, double t, int order, double* out) const {
  // Piegl & Tiller A2.3: table of basis values and knot differences, then the
  // derivative recurrence. Derivatives above p are zero.
  const int p = p_;
  // On the stack up to degree 15: the geometry is evaluated point by point at every side of an
  // adaptive mesh, and four heap arrays per call were a fifth of that.
  constexpr int kStackDegree = 15;
  double stack[(kStackDegree + 1) * (kStackDegree + 5)];
  std::vector<double> heap;
  double* work = stack;
  if (p > kStackDegree) {
    heap.resize(size_t(p + 1) * (p + 5));
    work = heap.data();
  }
  double *ndu = work, *left = ndu + (p + 1) * (p + 1), *right = left + (p + 1), *a_work = right + (p + 1);
  auto NDU = [&](int i, int j) -> double& { return ndu[i * (p + 1) + j]; };
  NDU(0, 0) = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = t - knots_[s + 1 - j];
    right[j] = knots_[s + j] - t;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      NDU(j, r) = right[r + 1] + left[j - r];
      const double temp = NDU(r, j - 1) / NDU(j, r);
      NDU(r, j) = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    NDU(j, j) = saved;
  }
  for (int j = 0; j <= p; ++j) out[j] = NDU(j, p);
  for (int k = 1; k <= order; ++k)
    for (int j = 0; j <= p; ++j) out[k * (p + 1) + j] = 0.0;
  for (int r = 0; r <= p; ++r) {
    double* a0 = a_work;
    double* a1 = a_work + (p + 1);
    a0[0] = 1.0;
    for (int k = 1; k <= std::min(order, p); ++k) {
      double d = 0.0;
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a1[0] = a0[0] / NDU(pk + 1, rk);
        d = a1[0] * NDU(rk, pk);
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a1[j] = (a0[j] - a0[j - 1]) / NDU(pk + 1, rk + j);
        d += a1[j] * NDU(rk + j, pk);
      }
      if (r <= pk) {
        a1[k] = -a0[k - 1] / NDU(pk + 1, r);
        d += a1[k] * NDU(r, pk);
      }
      out[k * (p + 1) + r] = d;
      std::swap(a0, a1);
    }
  }
  double factor = p;
  for (int k = 1; k <= std::min(order, p); ++k) {
    for (int j = 0; j <= p; ++j) out[k * (p + 1) + j] *= factor;
    factor *= (p - k);
  }
}

std::vector<double> BSplineBasis1D::breakpoints() const {
  std::vector<double> b;
  for (int i = p_; i <= num_functions(); ++i)
    if (b.empty() || knots_[i] != b.back()) b.push_back(knots_[i]);
  return b;
}

std::vector<int> BSplineBasis1D::multiplicities() const {
  std::vector<int> m;
  for (double b : breakpoints())
    m.push_back(static_cast<int>(std::count(knots_.begin(), knots_.end(), b)));
  return m;
}

std::vector<double> greville_abscissae(const std::vector<double>& knots, int degree) {
  if (degree < 1 || knots.size() < size_t(degree) + 2)
    throw std::invalid_argument("greville_abscissae: degree at least 1 and at least degree + 2 knots");
  std::vector<double> xi(knots.size() - degree - 1);
  for (size_t i = 0; i < xi.size(); ++i) {
    double sum = 0;
    for (int k = 1; k <= degree; ++k) sum += knots[i + k];
    xi[i] = sum / degree;
  }
  return xi;
}

BSplineBasis1D consecutive_functions(const BSplineBasis1D& basis, int first, int count) {
  const int p = basis.degree();
  if (first < 0 || count <= p || first + count > basis.num_functions())
    throw std::invalid_argument("consecutive_functions: functions " + std::to_string(first) + " .. " +
                                std::to_string(first + count - 1) + " of " + std::to_string(basis.num_functions()) +
                                " do not span an element of degree " + std::to_string(p));
  const std::vector<double>& k = basis.knots();
  return BSplineBasis1D(p, std::vector<double>(k.begin() + first, k.begin() + first + count + p + 1));
}

std::vector<int> BSplineBasis1D::element_spans() const {
  std::vector<int> spans;
  for (int s = p_; s < num_functions(); ++s)
    if (knots_[s] < knots_[s + 1]) spans.push_back(s);
  return spans;
}

double de_boor(const BSplineBasis1D& basis, std::span<const double> c, double t) {
  const int p = basis.degree();
  const auto& U = basis.knots();
  const int k = basis.find_span(t);
  std::vector<double> d(p + 1);
  for (int j = 0; j <= p; ++j) d[j] = c[j + k - p];
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = j + k - p;
      const double alpha = (t - U[i]) / (U[i + p + 1 - r] - U[i]);
      d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
    }
  return d[p];
}

namespace {

// Boehm insertion of t into a (possibly local) knot vector L with coefficient rows Q.
// Only the knots L[i], L[i+p] of the affected functions are used, so this is exact
// on a local window of 2p+2 knots too.
void boehm(std::vector<double>& L, Eigen::MatrixXd& Q, int p, double t) {
  int s = static_cast<int>(std::upper_bound(L.begin(), L.end(), t) - L.begin()) - 1;
  int mult = 0;
  while (s - mult >= 0 && L[s - mult] == t) ++mult;
  Eigen::MatrixXd R(Q.rows() + 1, Q.cols());
  for (int i = 0; i <= s - p; ++i) R.row(i) = Q.row(i);
  for (int i = std::max(s - p + 1, 0); i <= s - mult; ++i) {
    const double alpha = bspline_kernel::split_weights<double>({L.data() + i, std::size_t(p) + 2}, t).first;
    R.row(i) = alpha * Q.row(i) + (1.0 - alpha) * Q.row(i - 1);
  }
  for (int i = s - mult + 1; i < R.rows(); ++i) R.row(i) = Q.row(i - 1);
  L.insert(L.begin() + s + 1, t);
  Q = std::move(R);
}

}  // namespace

BSplineBasis1D insert_knot(const BSplineBasis1D& basis, Eigen::MatrixXd& coefficients,
                           double t) {
  if (!(t > basis.domain_begin() && t < basis.domain_end()))
    throw std::invalid_argument("knot " + num(t) + " to insert is not inside the domain");
  if (coefficients.rows() != basis.num_functions())
    throw std::invalid_argument("insert_knot: coefficient count does not match the basis");
  std::vector<double> L = basis.knots();
  boehm(L, coefficients, basis.degree(), t);
  return BSplineBasis1D(basis.degree(), std::move(L));
}

std::vector<Eigen::MatrixXd> bezier_extraction(const BSplineBasis1D& basis) {
  const int p = basis.degree();
  const auto& U = basis.knots();
  std::vector<Eigen::MatrixXd> result;
  for (int k : basis.element_spans()) {
    const double a = U[k], b = U[k + 1];
    std::vector<double> L(U.begin() + (k - p), U.begin() + (k + p + 2));
    Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(p + 1, p + 1);
    int mult_a = 0, mult_b = 0;
    for (int i = 0; i <= p; ++i) mult_a += (L[i] == a);
    for (int i = p + 1; i <= 2 * p + 1; ++i) mult_b += (L[i] == b);
    for (int r = mult_a; r < p; ++r) boehm(L, Q, p, a);
    for (int r = mult_b; r < p; ++r) boehm(L, Q, p, b);
    const int s = static_cast<int>(std::upper_bound(L.begin(), L.end(), a) - L.begin()) - 1;
    // Rows s-p..s of Q are the Bernstein coefficients of the p+1 original functions.
    result.push_back(Q.middleRows(s - p, p + 1).transpose());
  }
  return result;
}

BSplineBasis1D elevated_basis(const BSplineBasis1D& basis, int r) {
  std::vector<double> k;
  const auto b = basis.breakpoints();
  const auto m = basis.multiplicities();
  for (size_t i = 0; i < b.size(); ++i) k.insert(k.end(), m[i] + r, b[i]);
  return BSplineBasis1D(basis.degree() + r, std::move(k));
}

BSplineBasis1D elevate_degree(const BSplineBasis1D& basis, Eigen::MatrixXd& coefficients, int r) {
  BSplineBasis1D fine = elevated_basis(basis, r);
  coefficients = refinement_matrix(basis, fine) * coefficients;
  return fine;
}

namespace {

// Degree elevation matrix (elevated.num_functions() x coarse.num_functions()): the Bezier
// coefficients of every coarse function, elevated exactly, then fitted by least squares
// with the elevated basis' Bezier coefficients over ALL elements at once. The fit is exact
// (the functions lie in the elevated space), and unlike inverting one element's extraction
// it stays well conditioned on strongly graded knot vectors (B-splines are uniformly well
// conditioned, whatever the knot spacing).
Eigen::MatrixXd elevation_matrix(const BSplineBasis1D& coarse, const BSplineBasis1D& elevated) {
  const int pc = coarse.degree(), pf = elevated.degree();
  const auto Cc = bezier_extraction(coarse);
  const auto Cf = bezier_extraction(elevated);
  const auto sc = coarse.element_spans(), sf = elevated.element_spans();
  const Eigen::MatrixXd E = degree_elevation_matrix(pc, pf - pc);
  const Eigen::Index rows = static_cast<Eigen::Index>(sc.size()) * (pf + 1);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, elevated.num_functions());
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(rows, coarse.num_functions());
  for (size_t e = 0; e < sc.size(); ++e) {
    const Eigen::Index r0 = static_cast<Eigen::Index>(e) * (pf + 1);
    A.block(r0, sf[e] - pf, pf + 1, pf + 1) = Cf[e].transpose();
    B.block(r0, sc[e] - pc, pf + 1, pc + 1) = E * Cc[e].transpose();
  }
  return A.colPivHouseholderQr().solve(B);
}

// The knot insertion matrix of two bases of one degree, the fine knots containing the coarse
// ones, by the Oslo algorithm (Lyche and Morken, Spline Methods, ch. 4): row i holds the
// discrete B-splines at i, the coarse B-splines of the span holding fine knot i evaluated by
// the Cox-de Boor recursion with argument fine_knot[i + k] at level k. O(p^2) per row and
// sparse from the start, where repeated Boehm insertion into a dense matrix costs O(n^2) per
// knot (a multigrid hierarchy on 4 096 elements inserts 2 048 knots).
Eigen::SparseMatrix<double> knot_insertion_matrix(const BSplineBasis1D& coarse, const BSplineBasis1D& fine) {
  const int p = coarse.degree(), nc = coarse.num_functions(), nf = fine.num_functions();
  const auto& t = coarse.knots();
  const auto& tau = fine.knots();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(nf) * (p + 1));
  std::vector<double> b(p + 1), next(p + 1);
  auto ratio = [](double a, double d) { return d > 0 ? a / d : 0.0; };
  int mu = p;
  for (int i = 0; i < nf; ++i) {
    // The coarse span [t_mu, t_mu+1) holding tau_i (non-empty, inside the domain).
    while (mu + 1 < nc && t[mu + 1] <= tau[i]) ++mu;
    b[0] = 1;
    for (int k = 1; k <= p; ++k) {
      const double x = tau[i + k];
      // b holds the k functions mu-k+1..mu of degree k-1; next the k+1 functions mu-k..mu.
      for (int j = 0; j <= k; ++j) {
        const int r = mu - k + j;
        const double left = j > 0 ? ratio(x - t[r], t[r + k] - t[r]) * b[j - 1] : 0.0;
        const double right = j < k ? ratio(t[r + k + 1] - x, t[r + k + 1] - t[r + 1]) * b[j] : 0.0;
        next[j] = left + right;
      }
      std::copy(next.begin(), next.begin() + k + 1, b.begin());
    }
    for (int j = 0; j <= p; ++j)
      if (b[j] != 0) entries.emplace_back(i, mu - p + j, b[j]);
  }
  Eigen::SparseMatrix<double> T(nf, nc);
  T.setFromTriplets(entries.begin(), entries.end());
  return T;
}

}  // namespace

Eigen::SparseMatrix<double> refinement_matrix(const BSplineBasis1D& coarse,
                                              const BSplineBasis1D& fine) {
  const int pc = coarse.degree(), pf = fine.degree();
  if (pf < pc) throw std::invalid_argument("refinement_matrix: fine degree below coarse degree");
  if (coarse.domain_begin() != fine.domain_begin() || coarse.domain_end() != fine.domain_end())
    throw std::invalid_argument("refinement_matrix: the two bases have different domains");
  // 1. Elevate on the coarse mesh; 2. insert the missing knots (Oslo on open knot vectors of one
  // degree, else Boehm's algorithm).
  const BSplineBasis1D mid = elevated_basis(coarse, pf - pc);
  std::vector<double> L = mid.knots();
  const auto& Uf = fine.knots();
  for (double k : L)
    if (std::count(Uf.begin(), Uf.end(), k) < std::count(L.begin(), L.end(), k))
      throw std::invalid_argument("refinement_matrix: the fine space does not contain the coarse one at knot " +
                                  num(k));
  std::vector<std::pair<double, long>> missing;  // knot, how many more times
  for (size_t i = 0; i < Uf.size();) {
    size_t j = i;
    while (j < Uf.size() && Uf[j] == Uf[i]) ++j;
    // (Never negative: every knot of L was counted in Uf above.)
    missing.emplace_back(Uf[i], static_cast<long>(j - i) - std::count(L.begin(), L.end(), Uf[i]));
    i = j;
  }
  if (pf == pc && coarse.is_open() && fine.is_open()) return knot_insertion_matrix(coarse, fine);
  Eigen::MatrixXd T = pf > pc ? elevation_matrix(coarse, mid)
                              : Eigen::MatrixXd::Identity(coarse.num_functions(), coarse.num_functions());
  for (const auto& [knot, times] : missing)
    for (long k = 0; k < times; ++k) boehm(L, T, pf, knot);
  return T.sparseView(0.0, 0.0);
}

}  // namespace knotwork

namespace knotwork {
Eigen::VectorXd single_bspline_bernstein(std::span<const double> knots, double a, double b) {
  const int d = static_cast<int>(knots.size()) - 2;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(d + 1);
  if (b <= knots.front() || a >= knots.back()) return out;
  // The span [knots[m], knots[m+1]] holding [a, b]. Padding with d knots on each side makes
  // the function number d of a basis whose domain is its support; on span s = m + d the alive
  // functions are s-d..s with coefficients e_d. The k-th Bernstein coefficient on [a, b] is
  // the blossom at (a^(d-k), b^k): de Boor's algorithm with argument u_r at level r. O(d^3)
  // per piece; extracting the whole padded basis instead was half of a knot-segment Bezier
  // mesh in adaptive runs.
  int m = -1;
  for (int i = 0; i <= d; ++i)
    if (knots[i] < knots[i + 1] && knots[i] <= a && b <= knots[i + 1]) {
      m = i;
      break;
    }
  if (m < 0) throw std::invalid_argument("single_bspline_bernstein: [a, b] is not inside one knot span");
  auto U = [&](int i) {  // the padded knot vector
    return i < d ? knots.front() - 1.0 : i < 2 * d + 2 ? knots[i - d] : knots.back() + 1.0;
  };
  const int s = m + d;
  std::vector<double> c(d + 1);  // c[j]: coefficient of function s - d + j
  for (int k = 0; k <= d; ++k) {
    std::fill(c.begin(), c.end(), 0.0);
    c[d - (s - d)] = 1.0;
    for (int r = 1; r <= d; ++r) {
      const double u = r <= d - k ? a : b;
      for (int j = d; j >= r; --j) {
        const int i = s - d + j;
        const double alpha = (u - U(i)) / (U(i + d + 1 - r) - U(i));
        c[j] = (1.0 - alpha) * c[j - 1] + alpha * c[j];
      }
    }
    out[k] = c[d];
  }
  return out;
}
}  // namespace knotwork
