#include "solver/fast_diagonalization_3d.hpp"

#include <algorithm>
#include <cmath>

namespace knotwork {

namespace {

// Up to 8 indices spread over 0..n-1.
std::vector<int> sample(int n) {
  std::vector<int> v;
  const int m = std::min(n, 8);
  for (int k = 0; k < m; ++k) v.push_back(m == 1 ? 0 : static_cast<int>((static_cast<long>(k) * (n - 1)) / (m - 1)));
  return v;
}

}  // namespace

SeparableVolumeCoefficients SeparableVolumeCoefficients::fit(const std::array<int, 3>& n,
                                                             const std::function<std::array<double, 3>(int, int, int)>& c) {
  const std::array<std::vector<int>, 3> samples{sample(n[0]), sample(n[1]), sample(n[2])};
  // f[d][k][i]: the mean of log c_dd over the sampled elements whose index in direction k is i
  // (all i of direction k, the samples in the other two). For log c_dd = sum_k g_dk(x_k), f[d][k]
  // is g_dk up to a constant, and the constants are fixed by the mean over the sampled grid.
  std::array<std::array<std::vector<double>, 3>, 3> f;
  std::array<double, 3> grid_mean{};
  for (int k = 0; k < 3; ++k) {
    for (int d = 0; d < 3; ++d) f[d][k].assign(n[k], 0.0);
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double count = double(samples[a].size() * samples[b].size());
    for (int i = 0; i < n[k]; ++i)
      for (int ja : samples[a])
        for (int jb : samples[b]) {
          std::array<int, 3> at;
          at[k] = i, at[a] = ja, at[b] = jb;
          const std::array<double, 3> value = c(at[0], at[1], at[2]);
          for (int d = 0; d < 3; ++d) f[d][k][i] += std::log(std::max(value[d], 1e-300)) / count;
        }
  }
  for (int d = 0; d < 3; ++d) {
    double sum = 0;
    for (int i : samples[0]) sum += f[d][0][i];
    grid_mean[d] = sum / double(samples[0].size());  // = the mean of log c_dd over the sampled grid
  }
  // The shape of each factor: f minus its mean over the samples. mu_k: the geometric mean of
  // the shapes that the two terms carrying M_k give it; tau_d: its own shape, and the whole
  // term's level (grid_mean[d]) less what the mu's carry (their shapes average zero).
  const auto shape = [&](int d, int k) {
    double mean = 0;
    for (int i : samples[k]) mean += f[d][k][i];
    mean /= double(samples[k].size());
    std::vector<double> s(f[d][k]);
    for (double& x : s) x -= mean;
    return s;
  };
  SeparableVolumeCoefficients r;
  for (int k = 0; k < 3; ++k) {
    const std::vector<double> s1 = shape((k + 1) % 3, k), s2 = shape((k + 2) % 3, k), own = shape(k, k);
    r.mu[k].resize(n[k]);
    r.tau[k].resize(n[k]);
    for (int i = 0; i < n[k]; ++i) {
      r.mu[k][i] = std::exp((s1[i] + s2[i]) / 2);
      r.tau[k][i] = std::exp(own[i] + grid_mean[k]);
    }
  }
  return r;
}

bool tensor_free_indices_3d(const std::array<int, 3>& n, const DofLayout& layout, std::array<std::vector<int>, 3>& free) {
  for (auto& f : free) f.clear();
  const long total = long(n[0]) * n[1] * n[2];
  if (static_cast<long>(layout.dof.size()) != total) return false;
  std::array<std::vector<bool>, 3> is_free{std::vector<bool>(n[0]), std::vector<bool>(n[1]), std::vector<bool>(n[2])};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (layout.dof[i + long(n[0]) * (j + long(n[1]) * k)] >= 0) is_free[0][i] = is_free[1][j] = is_free[2][k] = true;
  for (int d = 0; d < 3; ++d)
    for (int i = 0; i < n[d]; ++i)
      if (is_free[d][i]) free[d].push_back(i);
  const long a = long(free[0].size()), b = long(free[1].size()), c = long(free[2].size());
  if (a * b * c != layout.num_free()) return false;
  for (long z = 0; z < c; ++z)
    for (long y = 0; y < b; ++y)
      for (long x = 0; x < a; ++x)
        if (layout.dof[free[0][x] + long(n[0]) * (free[1][y] + long(n[1]) * free[2][z])] != x + a * (y + b * z)) return false;
  return true;
}

namespace {

class FastDiagonalization3d final : public Preconditioner {
 public:
  FastDiagonalization3d(std::array<Eigen::MatrixXd, 3> U, const std::array<Eigen::VectorXd, 3>& lambda, Eigen::VectorXd scale,
                        double shift)
      : U_(std::move(U)), scale_(std::move(scale)) {
    for (int d = 0; d < 3; ++d) n_[d] = static_cast<int>(lambda[d].size());
    inverse_.resize(scale_.size());
    // The three sums are positive for a definite operator; a zero sum (a constant mode of a
    // singular one) is left out rather than divided by.
    double largest = 0;
    for (int d = 0; d < 3; ++d) largest += lambda[d].size() ? lambda[d].cwiseAbs().maxCoeff() : 0.0;
    Eigen::Index at = 0;
    for (int k = 0; k < n_[2]; ++k)
      for (int j = 0; j < n_[1]; ++j)
        for (int i = 0; i < n_[0]; ++i, ++at) {
          const double sum = lambda[0][i] + lambda[1][j] + lambda[2][k] + shift;
          inverse_[at] = sum > 1e-14 * largest ? 1.0 / sum : 0.0;
        }
  }

  // z = D^{-1/2} (U_w (x) U_v (x) U_u) Lambda^{-1} (U_w (x) U_v (x) U_u)^T D^{-1/2} r, the vector
  // as an n_u x n_v x n_w array (u fastest): each factor acts as one product along its mode.
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    // z itself is the first work array (each pass of modes swaps it with b and back), so that
    // one vector of the problem's size is kept, not two.
    thread_local Eigen::VectorXd b;
    z = r.cwiseProduct(scale_);
    b.resize(z.size());
    modes(z, b, true);  // z <- U^T z (b is workspace)
    z.array() *= inverse_.array();
    modes(z, b, false);  // z <- U z
    z.array() *= scale_.array();
  }

 private:
  // x <- (U_w (x) U_v (x) U_u)^T x (transpose) or (U_w (x) U_v (x) U_u) x, through y.
  void modes(Eigen::VectorXd& x, Eigen::VectorXd& y, bool transpose) const {
    const int nu = n_[0], nv = n_[1], nw = n_[2];
    // u: Y = op(U_u) X, X as nu x (nv nw).
    blas_gemm(transpose, false, nu, nv * nw, nu, U_[0].data(), nu, x.data(), nu, y.data(), nu);
    // v: for each w-slice, X_k = Y_k op(U_v)^T, Y_k as nu x nv: (U_v^T applied along v) is Y_k U_v.
    for (int k = 0; k < nw; ++k) {
      const long offset = long(nu) * nv * k;
      blas_gemm(false, !transpose, nu, nv, nv, y.data() + offset, nu, U_[1].data(), nv, x.data() + offset, nu);
    }
    // w: Y = X op(U_w)^T, X as (nu nv) x nw.
    blas_gemm(false, !transpose, nu * nv, nw, nw, x.data(), nu * nv, U_[2].data(), nw, y.data(), nu * nv);
    x.swap(y);
  }

  std::array<Eigen::MatrixXd, 3> U_;
  std::array<int, 3> n_{};
  Eigen::VectorXd inverse_, scale_;  // scale_: D^{-1/2} in dof order
};

}  // namespace

std::unique_ptr<Preconditioner> fast_diagonalization_3d(const std::array<BSplineBasis1D, 3>& spaces, const DofLayout& layout,
                                                        const Eigen::VectorXd& diagonal,
                                                        const SeparableVolumeCoefficients& geometry,
                                                        const std::array<bool, 6>& nitsche, double nitsche_factor) {
  const std::array<int, 3> n{spaces[0].num_functions(), spaces[1].num_functions(), spaces[2].num_functions()};
  std::array<std::vector<int>, 3> free;
  if (!tensor_free_indices_3d(n, layout, free)) return nullptr;
  std::array<UnivariatePair, 3> pair;
  std::array<Eigen::MatrixXd, 3> U;
  std::array<Eigen::VectorXd, 3> lambda;
  for (int d = 0; d < 3; ++d) {
    pair[d] = univariate_pair(spaces[d], geometry.mu[d], geometry.tau[d], nitsche[2 * d], nitsche[2 * d + 1], nitsche_factor);
    // Directions with the same knots, free indices, weights and ends share one decomposition
    // (the cube's three).
    int same = -1;
    for (int e = 0; e < d && same < 0; ++e)
      if (spaces[e].degree() == spaces[d].degree() && spaces[e].knots() == spaces[d].knots() && free[e] == free[d] &&
          geometry.mu[e] == geometry.mu[d] && geometry.tau[e] == geometry.tau[d] && nitsche[2 * e] == nitsche[2 * d] &&
          nitsche[2 * e + 1] == nitsche[2 * d + 1])
        same = e;
    if (same >= 0) {
      U[d] = U[same];
      lambda[d] = lambda[same];
    } else {
      diagonalize(pair[d], free[d], U[d], lambda[d]);
    }
  }
  // D = diag(K) / diag(P): P_dd = sum over directions of K's diagonal there times the masses'.
  std::array<Eigen::VectorXd, 3> k_diag, m_diag;
  for (int d = 0; d < 3; ++d) {
    k_diag[d] = pair[d].stiffness.diagonal();
    m_diag[d] = pair[d].mass.diagonal();
  }
  Eigen::VectorXd scale(layout.num_free());
  Eigen::Index at = 0;
  for (int c : free[2])
    for (int b : free[1])
      for (int a : free[0]) {
        const double p = k_diag[0][a] * m_diag[1][b] * m_diag[2][c] + m_diag[0][a] * k_diag[1][b] * m_diag[2][c] +
                         m_diag[0][a] * m_diag[1][b] * k_diag[2][c] + geometry.shift * m_diag[0][a] * m_diag[1][b] * m_diag[2][c];
        scale[at] = diagonal[at] > 0 && p > 0 ? std::sqrt(p / diagonal[at]) : 1.0;
        ++at;
      }
  return std::make_unique<FastDiagonalization3d>(std::move(U), lambda, std::move(scale), geometry.shift);
}

}  // namespace knotwork
