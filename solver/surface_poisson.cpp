#include "solver/surface_poisson.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include "basis/bspline_basis.hpp"
#include "quadrature/bernstein.hpp"

namespace knotwork {

namespace {

// Second derivatives of the tensor Bernstein basis at the points of bernstein_table(p, p, nq,
// nq), in its point and function order (the Bernstein basis is the B-spline basis on
// 0^(p+1) 1^(p+1), whose derivatives BSplineBasis1D gives). Built once per (p, nq).
struct SecondDerivativeTable {
  Eigen::MatrixXd uu, uv, vv;
};

const SecondDerivativeTable& second_derivative_table(int p, int nq) {
  static std::mutex lock;
  static std::map<std::pair<int, int>, SecondDerivativeTable> cache;
  const std::lock_guard<std::mutex> guard(lock);
  const auto found = cache.find({p, nq});
  if (found != cache.end()) return found->second;
  std::vector<double> knots(p + 1, 0.0);
  knots.insert(knots.end(), p + 1, 1.0);
  const BSplineBasis1D bernstein(p, knots);
  const BernsteinTable& t = bernstein_table(p, p, nq, nq);
  const int nb = p + 1;
  // d[i](order, a): derivative `order` of Bernstein a at node i.
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>> d(nq, Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>(3, nb));
  for (int i = 0; i < nq; ++i) bernstein.evaluate_derivatives(p, t.rule_u.nodes[i], p >= 2 ? 2 : 1, d[i].data());
  if (p < 2)
    for (auto& m : d) m.row(2).setZero();
  SecondDerivativeTable s;
  s.uu.resize(nq * nq, nb * nb);
  s.uv.resize(nq * nq, nb * nb);
  s.vv.resize(nq * nq, nb * nb);
  for (int j = 0; j < nq; ++j)
    for (int i = 0; i < nq; ++i)
      for (int c = 0; c < nb; ++c)
        for (int a = 0; a < nb; ++a) {
          s.uu(i + nq * j, a + nb * c) = d[i](2, a) * d[j](0, c);
          s.uv(i + nq * j, a + nb * c) = d[i](1, a) * d[j](1, c);
          s.vv(i + nq * j, a + nb * c) = d[i](0, a) * d[j](2, c);
        }
  return cache.emplace(std::make_pair(p, nq), std::move(s)).first->second;
}

// Geometry of one cell at the points of a Gauss rule: point, first and second derivatives.
struct SurfacePoints {
  Eigen::MatrixX3d x, xu, xv, xuu, xuv, xvv;
};

SurfacePoints surface_at(const SurfaceCell& cell, const BernsteinTable& t, bool second = false) {
  SurfacePoints s;
  s.x.noalias() = t.value * cell.points;
  s.xu.noalias() = t.d_u * cell.points;
  s.xv.noalias() = t.d_v * cell.points;
  if (second) {
    const SecondDerivativeTable& d = second_derivative_table(cell.degree, t.rule_u.size());
    s.xuu.noalias() = d.uu * cell.points;
    s.xuv.noalias() = d.uv * cell.points;
    s.xvv.noalias() = d.vv * cell.points;
  }
  return s;
}

struct Metric {
  Eigen::Matrix2d inverse;  // G^{-1}
  double area = 0;          // sqrt(det G) = |x_u x x_v|
  Eigen::Vector3d normal;
};

Metric metric(const Eigen::Vector3d& xu, const Eigen::Vector3d& xv) {
  Metric m;
  Eigen::Matrix2d G;
  G << xu.dot(xu), xu.dot(xv), xu.dot(xv), xv.dot(xv);
  const Eigen::Vector3d c = xu.cross(xv);
  m.area = c.norm();
  m.normal = c / m.area;
  m.inverse = G.inverse();
  return m;
}

// -Laplace_Beltrami(u) + reaction u at a point of the discrete surface, from the exact
// solution's ambient derivatives and the surface's curvature there.
double derived_source(std::array<ExpressionEvaluator, 3>& gradient,
                      std::array<std::array<std::optional<ExpressionEvaluator>, 3>, 3>& hessian,
                      ExpressionEvaluator& value, double reaction, const SurfacePoints& s, int q, const Metric& m) {
  const double x = s.x(q, 0), y = s.x(q, 1), z = s.x(q, 2);
  Eigen::Vector3d g;
  Eigen::Matrix3d H;
  for (int i = 0; i < 3; ++i) {
    g(i) = gradient[i](x, y, z);
    for (int j = 0; j < 3; ++j) H(i, j) = (*hessian[i][j])(x, y, z);
  }
  const Eigen::Vector3d& n = m.normal;
  const double b_uu = s.xuu.row(q).dot(n), b_uv = s.xuv.row(q).dot(n), b_vv = s.xvv.row(q).dot(n);
  const double kappa = -(m.inverse(0, 0) * b_uu + 2 * m.inverse(0, 1) * b_uv + m.inverse(1, 1) * b_vv);
  const double laplace_beltrami = H.trace() - n.dot(H * n) - kappa * g.dot(n);
  return -laplace_beltrami + (reaction != 0 ? reaction * value(x, y, z) : 0.0);
}

struct Evaluators {
  ExpressionEvaluator value;
  std::array<ExpressionEvaluator, 3> gradient;
  std::array<std::array<std::optional<ExpressionEvaluator>, 3>, 3> hessian;
  explicit Evaluators(const SurfaceExactSolution& e)
      : value(e.u), gradient{ExpressionEvaluator(e.gradient[0]), ExpressionEvaluator(e.gradient[1]),
                             ExpressionEvaluator(e.gradient[2])} {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) hessian[i][j].emplace(e.hessian[i][j]);
  }
};

void check_cells(const BezierMesh& mesh, const std::vector<SurfaceCell>& cells) {
  if (static_cast<int>(cells.size()) != mesh.num_cells())
    throw std::invalid_argument("surface: " + std::to_string(cells.size()) + " geometry cells for a mesh of " +
                                std::to_string(mesh.num_cells()));
  if (mesh.is_rational()) throw std::invalid_argument("surface: rational spaces are not supported");
}

}  // namespace

SurfaceSolution solve_surface_poisson(const BezierMesh& mesh, const std::vector<SurfaceCell>& cells,
                                      const SurfaceProblem& problem, const QuadratureOptions& quadrature) {
  check_cells(mesh, cells);
  if (!problem.source && !problem.exact)
    throw std::invalid_argument("surface problem: neither a source nor an exact solution to derive it from");
  if (problem.reaction < 0) throw std::invalid_argument("surface problem: reaction must be >= 0");
  const int n = mesh.num_functions();
  std::vector<Eigen::Triplet<double>> k_entries, m_entries;
  Eigen::VectorXd load = Eigen::VectorXd::Zero(n), integral = Eigen::VectorXd::Zero(n);
  std::optional<Evaluators> exact;
  if (problem.exact) exact.emplace(*problem.exact);
  std::optional<ExpressionEvaluator> source;
  if (problem.source) source.emplace(*problem.source);
  SurfaceSolution sol;
  sol.num_functions = n;

  for (int c = 0; c < mesh.num_cells(); ++c) {
    const int p = cells[c].degree;
    const int nq = quadrature.points_u > 0 ? quadrature.points_u : p + 1;
    const BernsteinTable& t = bernstein_table(p, p, nq, nq);
    const Eigen::MatrixXd& C = mesh.extraction(c);
    if (C.cols() != t.num_functions())
      throw std::invalid_argument("surface: cell " + std::to_string(c) + " has degree " + std::to_string(p) +
                                  " but its extraction has " + std::to_string(C.cols()) + " Bernstein columns");
    // Second derivatives only for the curvature term of a derived source.
    const SurfacePoints s = surface_at(cells[c], t, !source);
    const Eigen::MatrixXd N = C * t.value.transpose(), Nu = C * t.d_u.transpose(), Nv = C * t.d_v.transpose();
    const Eigen::Index m = C.rows();
    Eigen::MatrixXd Ke = Eigen::MatrixXd::Zero(m, m), Me = Eigen::MatrixXd::Zero(m, m), D(m, 2);
    Eigen::VectorXd Fe = Eigen::VectorXd::Zero(m), Ie = Eigen::VectorXd::Zero(m);
    for (int q = 0; q < t.num_points(); ++q) {
      const Metric g = metric(s.xu.row(q).transpose(), s.xv.row(q).transpose());
      if (!(g.area > 0) || !std::isfinite(g.area))
        throw std::invalid_argument("surface: degenerate (zero area element) at a quadrature point of cell " +
                                    std::to_string(c));
      const double w = t.weight(q) * g.area;
      D.col(0) = Nu.col(q);
      D.col(1) = Nv.col(q);
      Ke.noalias() += w * D * g.inverse * D.transpose();
      Me.noalias() += w * N.col(q) * N.col(q).transpose();
      const double f = source ? (*source)(s.x(q, 0), s.x(q, 1), s.x(q, 2))
                              : derived_source(exact->gradient, exact->hessian, exact->value,
                                               problem.reaction, s, q, g);
      if (!std::isfinite(f))
        throw std::invalid_argument("surface: the source is not finite at a quadrature point of cell " +
                                    std::to_string(c));
      Fe += w * f * N.col(q);
      Ie += w * N.col(q);
    }
    const auto ids = mesh.functions(c);
    for (Eigen::Index a = 0; a < m; ++a) {
      load(ids[a]) += Fe(a);
      integral(ids[a]) += Ie(a);
      for (Eigen::Index b = 0; b < m; ++b) {
        k_entries.emplace_back(ids[a], ids[b], Ke(a, b));
        m_entries.emplace_back(ids[a], ids[b], Me(a, b));
      }
    }
  }
  Eigen::SparseMatrix<double> K(n, n), M(n, n);
  K.setFromTriplets(k_entries.begin(), k_entries.end());
  M.setFromTriplets(m_entries.begin(), m_entries.end());
  k_entries.clear();
  m_entries.clear();

  auto factor_and_solve = [&](const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b, CholeskyStats* stats) {
    SparseCholesky chol;
    const Eigen::SparseMatrix<double> lower = A.triangularView<Eigen::Lower>();
    chol.factorize(lower);
    Eigen::VectorXd x = chol.solve(b);
    if (stats) *stats = chol.stats();
    return x;
  };

  if (problem.reaction > 0) {
    const Eigen::SparseMatrix<double> A = K + problem.reaction * M;
    sol.matrix_nonzeros = Eigen::SparseMatrix<double>(A.triangularView<Eigen::Lower>()).nonZeros();
    sol.coefficients = factor_and_solve(A, load, &sol.cholesky);
    sol.area = integral.sum();
  } else {
    // The constant 1 in the basis: M c = (integral of each function).
    const Eigen::VectorXd one = factor_and_solve(M, integral, nullptr);
    sol.area = one.dot(integral);
    sol.source_mean = one.dot(load) / sol.area;
    const Eigen::VectorXd rhs = load - sol.source_mean * integral;
    Eigen::Index pin;
    one.cwiseAbs().maxCoeff(&pin);
    // K without row and column `pin`.
    std::vector<int> index(n);
    for (int i = 0, j = 0; i < n; ++i) index[i] = i == pin ? -1 : j++;
    std::vector<Eigen::Triplet<double>> entries;
    for (int col = 0; col < K.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it)
        if (index[it.row()] >= 0 && index[col] >= 0 && it.row() >= col)
          entries.emplace_back(index[it.row()], index[col], it.value());
    Eigen::SparseMatrix<double> reduced(n - 1, n - 1);
    reduced.setFromTriplets(entries.begin(), entries.end());
    sol.matrix_nonzeros = reduced.nonZeros();
    Eigen::VectorXd b(n - 1);
    for (int i = 0; i < n; ++i)
      if (index[i] >= 0) b(index[i]) = rhs(i);
    SparseCholesky chol;
    chol.factorize(reduced);
    const Eigen::VectorXd x = chol.solve(b);
    sol.cholesky = chol.stats();
    sol.coefficients = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i)
      if (index[i] >= 0) sol.coefficients(i) = x(index[i]);
    sol.coefficients -= (integral.dot(sol.coefficients) / sol.area) * one;  // zero mean
  }
  if (!sol.coefficients.allFinite()) throw std::runtime_error("the discrete solution has non-finite values");

  if (exact) {
    // Mean of the exact solution (removed when the problem fixes the mean to zero).
    double mean = 0;
    auto for_error_points = [&](auto&& visit) {
      for (int c = 0; c < mesh.num_cells(); ++c) {
        const int p = cells[c].degree;
        const int nq = quadrature.error_points_u > 0 ? quadrature.error_points_u : p + 2;
        const BernsteinTable& t = bernstein_table(p, p, nq, nq);
        const SurfacePoints s = surface_at(cells[c], t);
        visit(c, t, s);
      }
    };
    if (problem.reaction == 0) {
      for_error_points([&](int, const BernsteinTable& t, const SurfacePoints& s) {
        for (int q = 0; q < t.num_points(); ++q)
          mean += t.weight(q) * metric(s.xu.row(q).transpose(), s.xv.row(q).transpose()).area * exact->value(s.x(q, 0), s.x(q, 1), s.x(q, 2));
      });
      mean /= sol.area;
      sol.exact_mean = mean;
    }
    ErrorNorms e;
    for_error_points([&](int c, const BernsteinTable& t, const SurfacePoints& s) {
      const Eigen::MatrixXd& C = mesh.extraction(c);
      const auto ids = mesh.functions(c);
      Eigen::VectorXd local(C.rows());
      for (Eigen::Index a = 0; a < C.rows(); ++a) local(a) = sol.coefficients(ids[a]);
      const Eigen::VectorXd bern = C.transpose() * local;  // the solution's Bernstein coefficients
      const Eigen::VectorXd uh = t.value * bern, uh_u = t.d_u * bern, uh_v = t.d_v * bern;
      for (int q = 0; q < t.num_points(); ++q) {
        const Metric g = metric(s.xu.row(q).transpose(), s.xv.row(q).transpose());
        const double w = t.weight(q) * g.area;
        const double x = s.x(q, 0), y = s.x(q, 1), z = s.x(q, 2);
        const Eigen::Vector2d coeffs = g.inverse * Eigen::Vector2d(uh_u(q), uh_v(q));
        const Eigen::Vector3d grad_h = s.xu.row(q).transpose() * coeffs(0) + s.xv.row(q).transpose() * coeffs(1);
        Eigen::Vector3d grad(exact->gradient[0](x, y, z), exact->gradient[1](x, y, z), exact->gradient[2](x, y, z));
        grad -= grad.dot(g.normal) * g.normal;
        const double du = uh(q) - (exact->value(x, y, z) - mean);
        e.l2 += w * du * du;
        e.h1_semi += w * (grad_h - grad).squaredNorm();
      }
    });
    e.h1 = std::sqrt(e.l2 + e.h1_semi);
    e.l2 = std::sqrt(e.l2);
    e.h1_semi = std::sqrt(e.h1_semi);
    sol.errors = e;
  }
  return sol;
}

Eigen::MatrixX4d evaluate_surface_solution(const BezierMesh& mesh, const std::vector<SurfaceCell>& cells,
                                           const Eigen::VectorXd& coefficients, int cell, const Eigen::VectorXd& u,
                                           const Eigen::VectorXd& v) {
  check_cells(mesh, cells);
  const int p = cells[cell].degree;
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(p, p, u, v, B, Bu, Bv);
  const Eigen::MatrixXd& C = mesh.extraction(cell);
  const auto ids = mesh.functions(cell);
  Eigen::VectorXd local(C.rows());
  for (Eigen::Index a = 0; a < C.rows(); ++a) local(a) = coefficients(ids[a]);
  const Eigen::VectorXd bern = C.transpose() * local;
  const Eigen::MatrixX3d xu = Bu * cells[cell].points, xv = Bv * cells[cell].points;
  Eigen::MatrixX4d out(u.size(), 4);
  for (Eigen::Index q = 0; q < u.size(); ++q) {
    const Metric g = metric(xu.row(q).transpose(), xv.row(q).transpose());
    const Eigen::Vector2d coeffs = g.inverse * Eigen::Vector2d(Bu.row(q).dot(bern), Bv.row(q).dot(bern));
    out(q, 0) = B.row(q).dot(bern);
    out.block<1, 3>(q, 1) = xu.row(q) * coeffs(0) + xv.row(q) * coeffs(1);
  }
  return out;
}

}  // namespace knotwork
