#include "solver/residual_estimator.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <vector>

#include "quadrature/bernstein.hpp"
#include "quadrature/gauss_legendre.hpp"
#include "solver/cell_basis.hpp"
#include "solver/diffusion_at_points.hpp"
#include "solver/error_norms.hpp"
#include "solver/expression.hpp"

namespace knotwork {

namespace {

// The point of a cell's side at reference coordinate t along it.
void side_point(CellSide side, double t, double& u, double& v) {
  u = side == kSideBottom || side == kSideTop ? t : side == kSideRight ? 1 : 0;
  v = side == kSideLeft || side == kSideRight ? t : side == kSideTop ? 1 : 0;
}

// The reference derivatives (u_u, u_v) of u_h at (u, v) of a cell, from its Bernstein
// coefficients (index a + (p+1) b, a along u), kept from the interior pass for the sides.
// u_h is a polynomial on the cell: the estimator refuses rational spaces.
class ReferenceGradient {
 public:
  void operator()(const double* bernstein, int p, int q, double u, double v, double& su, double& sv) {
    bu_.resize(p + 1), du_.resize(p + 1), bv_.resize(q + 1), dv_.resize(q + 1);
    bernstein_values_and_derivatives(p, u, bu_.data(), du_.data());
    bernstein_values_and_derivatives(q, v, bv_.data(), dv_.data());
    su = 0, sv = 0;
    for (int b = 0; b <= q; ++b) {
      double along = 0, across = 0;
      for (int a = 0; a <= p; ++a) {
        const double c = bernstein[a + (p + 1) * b];
        along += du_[a] * c;
        across += bu_[a] * c;
      }
      su += bv_[b] * along;
      sv += dv_[b] * across;
    }
  }

 private:
  std::vector<double> bu_, du_, bv_, dv_;
};

// A and c of -div(A grad u) + c u at points, for one thread: A's entries (none: the identity;
// one: a I; three: a11, a12, a22) and their x and y derivatives, for div(A grad u_h).
class PointCoefficients {
 public:
  PointCoefficients(const PoissonProblem& problem, const std::vector<ExactSolution>& derivatives)
      : a_(problem.coefficients.diffusion), constant_reaction_(problem.reaction) {
    for (const ExactSolution& d : derivatives) {
      dx_.emplace_back(d.u_x);
      dy_.emplace_back(d.u_y);
    }
    if (!problem.coefficients.reaction.empty()) reaction_.emplace(problem.coefficients.reaction);
  }
  bool identity() const { return a_.identity(); }
  Eigen::Matrix2d A(double x, double y) { return a_(x, y); }
  // (div A)_j = sum_i d A_ij / d x_i at (x, y).
  Eigen::Vector2d divergence(double x, double y) {
    if (dx_.empty()) return Eigen::Vector2d::Zero();
    if (dx_.size() == 1) return Eigen::Vector2d(dx_[0](x, y), dy_[0](x, y));
    return Eigen::Vector2d(dx_[0](x, y) + dy_[1](x, y), dx_[1](x, y) + dy_[2](x, y));
  }
  double reaction(double x, double y) { return reaction_ ? (*reaction_)(x, y) : constant_reaction_; }

 private:
  DiffusionAtPoints a_;
  std::vector<ExpressionEvaluator> dx_, dy_;
  std::optional<ExpressionEvaluator> reaction_;
  double constant_reaction_;
};

}  // namespace

ErrorIndicators residual_indicators(const BezierMesh& mesh, const GeometryMap& geometry,
                                    const Eigen::VectorXd& coefficients, const PoissonProblem& problem) {
  if (geometry.parametric_dimension() == 3) return volume_residual_indicators(mesh, geometry, coefficients, problem);
  if (geometry.dimension() != 2) throw std::invalid_argument("the residual estimator is written for planar domains, not surfaces");
  if (mesh.is_rational()) throw std::invalid_argument("the residual estimator needs a polynomial (non-rational) space");
  if (!mesh.has_interfaces())
    throw std::invalid_argument("the residual estimator needs the mesh's cell interfaces, and this family gives none");
  {
    Eigen::MatrixXd probe;
    const Eigen::VectorXd half = Eigen::VectorXd::Constant(1, 0.5);
    if (mesh.num_cells() == 0 || !geometry.second_derivatives(0, half, half, probe))
      throw std::invalid_argument("the residual estimator needs a geometry map with second derivatives");
  }
  ErrorIndicators ind;
  ind.eta_squared = Eigen::VectorXd::Zero(mesh.num_cells());
  // The derivatives of A's entries, once (GiNaC is not thread-safe).
  std::vector<ExactSolution> diffusion;
  for (const Expression& a : problem.coefficients.diffusion) diffusion.push_back(differentiate_exact_solution(a));
  // Physical extent of each cell across its u and v directions (distance between the midpoints
  // of opposite sides; h_K is the larger), found in the interior pass.
  Eigen::VectorXd extent_u(mesh.num_cells()), extent_v(mesh.num_cells());
  // u_h's Bernstein coefficients on every cell, one block per cell, for the sides.
  std::vector<long> bernstein_offset(mesh.num_cells() + 1, 0);
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    bernstein_offset[c + 1] = bernstein_offset[c] + long(cell.degree_u + 1) * (cell.degree_v + 1);
  }
  std::vector<double> bernstein(bernstein_offset.back());
  // Interior residual h_K^2 ||f + Laplace(u_h)||^2 per cell (summed in cell order below, so
  // that the total does not depend on the threads).
  const ExpressionBatch compiled_source({problem.source});  // compiled once; each thread runs its own copy
#pragma omp parallel
  {
    ExpressionBatch f(compiled_source);
    PointCoefficients coefficient(problem, diffusion);
    GeometryAtPoints g, middles;
    Eigen::VectorXd mu(4), mv(4);
    mu << 0, 1, 0.5, 0.5;
    mv << 0.5, 0.5, 0, 1;
    // Reused from cell to cell: an adaptive loop estimates on up to 10^5 cells at every step,
    // and allocating these per cell cost a third of the interior residual's time.
    Eigen::MatrixXd second, B, Bu, Bv, Buu, Buv, Bvv;
    Eigen::VectorXd local, beta, U, U_u, U_v, U_uu, U_uv, U_vv;
    // The rule and the Bernstein tables depend on the degrees only: made again when they change.
    int rule_p = -1, rule_q = -1, n = 0;
    Eigen::VectorXd u, v, w;
#pragma omp for schedule(dynamic, 32)
    for (int c = 0; c < mesh.num_cells(); ++c) {
      const BezierCell& cell = mesh.cell(c);
      const int p = cell.degree_u, q = cell.degree_v;
      if (p != rule_p || q != rule_q) {
        const QuadratureRule1D ru = gauss_legendre(p + 2), rv = gauss_legendre(q + 2);
        n = static_cast<int>(ru.nodes.size() * rv.nodes.size());
        u.resize(n), v.resize(n), w.resize(n);
        for (size_t j = 0; j < rv.nodes.size(); ++j)
          for (size_t i = 0; i < ru.nodes.size(); ++i) {
            const size_t k = i + ru.nodes.size() * j;
            u[k] = ru.nodes[i];
            v[k] = rv.nodes[j];
            w[k] = ru.weights[i] * rv.weights[j];
          }
        tensor_bernstein(p, q, u, v, B, Bu, Bv);
        tensor_bernstein_second(p, q, u, v, Buu, Buv, Bvv);
        rule_p = p, rule_q = q;
      }
      geometry.evaluate_at_rule(c, p + 2, q + 2, g);  // the points u, v, from the map's tables
      geometry.second_derivatives(c, u, v, second);
      const auto ids = mesh.functions(c);
      local.resize(static_cast<Eigen::Index>(ids.size()));
      for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
      beta.noalias() = mesh.extraction(c).transpose() * local;  // Bernstein coefficients
      std::copy(beta.data(), beta.data() + beta.size(), bernstein.begin() + bernstein_offset[c]);
      geometry.evaluate(c, mu, mv, middles);
      extent_u[c] = (middles.x.row(1) - middles.x.row(0)).norm();
      extent_v[c] = (middles.x.row(3) - middles.x.row(2)).norm();
      // u_h's reference derivatives at the points: u_u, u_v, u_uu, u_uv, u_vv.
      U.noalias() = B * beta;
      U_u.noalias() = Bu * beta;
      U_v.noalias() = Bv * beta;
      U_uu.noalias() = Buu * beta;
      U_uv.noalias() = Buv * beta;
      U_vv.noalias() = Bvv * beta;
      f.evaluate(g.x.col(0).data(), g.x.col(1).data(), nullptr, n);
      const double* source = f.result(0);
      double integral = 0;
      for (int k = 0; k < n; ++k) {
        // Physical derivatives: grad = J^-T (u_u, u_v); Hess_ref = J^T Hess J + sum_i u_xi Hess(x_i).
        Eigen::Matrix2d J;
        J << g.jacobian(k, 0), g.jacobian(k, 1), g.jacobian(k, 2), g.jacobian(k, 3);
        const double det = J.determinant();
        const Eigen::Matrix2d Jinv = J.inverse();
        const Eigen::Vector2d grad = Jinv.transpose() * Eigen::Vector2d(U_u[k], U_v[k]);
        Eigen::Matrix2d H;
        H << U_uu[k], U_uv[k], U_uv[k], U_vv[k];
        for (int d = 0; d < 2; ++d) {
          Eigen::Matrix2d Hx;
          Hx << second(k, 3 * d), second(k, 3 * d + 1), second(k, 3 * d + 1), second(k, 3 * d + 2);
          H -= grad[d] * Hx;
        }
        // div(A grad u_h) = A : Hess u_h + (div A) . grad u_h, and the reaction -c u_h.
        const double x = g.x(k, 0), y = g.x(k, 1);
        const Eigen::Matrix2d hessian = Jinv.transpose() * H * Jinv;
        const double divergence = (coefficient.A(x, y).cwiseProduct(hessian)).sum() + coefficient.divergence(x, y).dot(grad);
        const double r = source[k] + divergence - coefficient.reaction(x, y) * U[k];
        integral += w[k] * std::abs(det) * r * r;
      }
      const double h = std::max(extent_u[c], extent_v[c]);
      ind.eta_squared[c] = h * h * integral;
    }
  }
  ind.residual_part = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) ind.residual_part += ind.eta_squared[c];
  // Gradient jumps across interior sides, half to each neighbour.
  const std::vector<CellInterface>& sides = mesh.interfaces();
  std::vector<double> side_value(sides.size()), side_max(sides.size());
#pragma omp parallel
  {
    // Per thread: the rule (per number of points), the map at both cells' points, and u_h's
    // reference gradient from the cells' Bernstein coefficients. (A rule per side made the
    // estimator of an adaptive run to 50 000 dofs 20% slower; u_h evaluated from the
    // functions, as elsewhere, twice as slow as from the coefficients kept.)
    int rule_n = -1;
    QuadratureRule1D rule;
    Eigen::VectorXd ua, va, ub, vb;
    GeometryAtPoints ga, gb;
    ReferenceGradient reference_gradient;
    PointCoefficients coefficient(problem, diffusion);
#pragma omp for schedule(dynamic, 64)
    for (size_t s = 0; s < sides.size(); ++s) {
      const CellInterface& e = sides[s];
      const BezierCell& lo = mesh.cell(e.cell_a);
      const BezierCell& hi = mesh.cell(e.cell_b);
      const int n = std::max({lo.degree_u, lo.degree_v}) + 2;
      if (n != rule_n) {
        rule = gauss_legendre(n);
        rule_n = n;
        ua.resize(n), va.resize(n), ub.resize(n), vb.resize(n);
      }
      for (int k = 0; k < n; ++k) {
        side_point(e.side_a, e.a_from + rule.nodes[k] * (e.a_to - e.a_from), ua[k], va[k]);
        side_point(e.side_b, e.b_from + rule.nodes[k] * (e.b_to - e.b_from), ub[k], vb[k]);
      }
      geometry.evaluate(e.cell_a, ua, va, ga);
      geometry.evaluate(e.cell_b, ub, vb, gb);
      const int col = e.side_a == kSideBottom || e.side_a == kSideTop ? 0 : 1;  // the tangent's reference direction
      double length = 0, integral = 0, biggest = 0;
      for (int k = 0; k < n; ++k) {
        // Physical gradients J^-T (u_u, u_v) on both sides of the point.
        double gradient[2][2];
        for (int side = 0; side < 2; ++side) {
          const GeometryAtPoints& g = side == 0 ? ga : gb;
          const BezierCell& cell = side == 0 ? lo : hi;
          const int c = side == 0 ? e.cell_a : e.cell_b;
          double su, sv;
          reference_gradient(bernstein.data() + bernstein_offset[c], cell.degree_u, cell.degree_v,
                             side == 0 ? ua[k] : ub[k], side == 0 ? va[k] : vb[k], su, sv);
          const double J0 = g.jacobian(k, 0), J1 = g.jacobian(k, 1), J2 = g.jacobian(k, 2), J3 = g.jacobian(k, 3);
          const double det = J0 * J3 - J1 * J2;
          gradient[side][0] = (J3 * su - J2 * sv) / det;
          gradient[side][1] = (J0 * sv - J1 * su) / det;
        }
        const double ds = std::hypot(ga.jacobian(k, col), ga.jacobian(k, 2 + col)) * std::abs(e.a_to - e.a_from) * rule.weights[k];
        // u_h is continuous: the jump of its gradient is normal, and that of the flux A grad u_h
        // is A times it.
        const Eigen::Vector2d step(gradient[0][0] - gradient[1][0], gradient[0][1] - gradient[1][1]);
        const double jump = coefficient.identity() ? std::hypot(step[0], step[1])
                                                   : (coefficient.A(ga.x(k, 0), ga.x(k, 1)) * step).norm();
        length += ds;
        integral += ds * jump * jump;
        biggest = std::max(biggest, jump);
      }
      side_value[s] = 0.5 * length * integral;
      side_max[s] = biggest;
    }
  }
  for (size_t s = 0; s < sides.size(); ++s) {
    ind.eta_squared[sides[s].cell_a] += side_value[s];
    ind.eta_squared[sides[s].cell_b] += side_value[s];
    ind.jump_part += 2 * side_value[s];
    ind.max_gradient_jump = std::max(ind.max_gradient_jump, side_max[s]);
  }
  // Neumann sides: h_E ||g - (A grad u_h).n||^2; Dirichlet sides by Nitsche's method: ||g - u_h||^2 / h_E.
  PointCoefficients coefficient(problem, diffusion);
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    for (int side = 0; side < 4; ++side) {
      const int id = cell.boundary[side];
      if (id < 0 || id >= static_cast<int>(problem.boundary.size())) continue;
      const BoundaryCondition& bc = problem.boundary[id];
      const bool weak_dirichlet =
          bc.kind == BoundaryKind::kDirichlet && problem.dirichlet_method == DirichletMethod::kNitsche;
      if (bc.kind != BoundaryKind::kNeumann && !weak_dirichlet) continue;
      const int n = std::max(cell.degree_u, cell.degree_v) + 2;
      const QuadratureRule1D rule = gauss_legendre(n);
      Eigen::VectorXd u(n), v(n);
      for (int k = 0; k < n; ++k) {
        const double t = rule.nodes[k];
        u[k] = side == kSideBottom ? t : side == kSideRight ? 1 : side == kSideTop ? 1 - t : 0;
        v[k] = side == kSideBottom ? 0 : side == kSideRight ? t : side == kSideTop ? 1 : 1 - t;
      }
      const Eigen::MatrixX3d sol = evaluate_solution(mesh, geometry, coefficients, c, u, v);
      GeometryAtPoints g;
      geometry.evaluate(c, u, v, g);
      // A flux vector given as data (h = F.n) is evaluated like grad u, without A.
      const bool flux_data = !weak_dirichlet && !bc.from_exact && !bc.flux.empty();
      ExpressionEvaluator data(flux_data        ? bc.flux[0]
                               : !bc.from_exact ? bc.value
                               : weak_dirichlet ? problem.exact->u
                                                : problem.exact->u_x);
      std::unique_ptr<ExpressionEvaluator> data_y;
      if (flux_data) data_y = std::make_unique<ExpressionEvaluator>(bc.flux[1]);
      else if (bc.from_exact && !weak_dirichlet) data_y = std::make_unique<ExpressionEvaluator>(problem.exact->u_y);
      double length = 0, integral = 0;
      for (int k = 0; k < n; ++k) {
        // Counter-clockwise tangent of the side; the outward normal is it turned clockwise
        // (for a positively oriented map; flipped otherwise).
        const double sign = (side == kSideTop || side == kSideLeft) ? -1.0 : 1.0;
        const int col = (side == kSideBottom || side == kSideTop) ? 0 : 1;
        double tx = sign * g.jacobian(k, col), ty = sign * g.jacobian(k, 2 + col);
        const double det = g.jacobian(k, 0) * g.jacobian(k, 3) - g.jacobian(k, 1) * g.jacobian(k, 2);
        const double len = std::hypot(tx, ty);
        double nx = ty / len, ny = -tx / len;
        if (det < 0) nx = -nx, ny = -ny;
        const double x = g.x(k, 0), y = g.x(k, 1);
        double r;
        if (weak_dirichlet) {
          r = data(x, y) - sol(k, 0);
        } else {
          // The flux (A grad u).n: from the exact solution, or the side's data; u_h's the same way.
          const Eigen::Matrix2d A = coefficient.A(x, y);
          const Eigen::Vector2d normal(nx, ny);
          const double gn = bc.from_exact ? (A * Eigen::Vector2d(data(x, y), (*data_y)(x, y))).dot(normal)
                            : flux_data     ? Eigen::Vector2d(data(x, y), (*data_y)(x, y)).dot(normal)
                                            : data(x, y);
          r = gn - (A * Eigen::Vector2d(sol(k, 1), sol(k, 2))).dot(normal);
        }
        const double ds = len * rule.weights[k];
        length += ds;
        integral += ds * r * r;
      }
      if (weak_dirichlet) {
        ind.eta_squared[c] += integral / length;
        ind.dirichlet_part += integral / length;
      } else {
        ind.eta_squared[c] += length * integral;
        ind.neumann_part += length * integral;
      }
    }
  }
  return ind;
}

std::vector<int> mark(const Eigen::VectorXd& eta_squared, const Marking& marking) {
  if (!(marking.theta > 0 && marking.theta <= 1)) throw std::invalid_argument("the marking fraction theta must be in (0, 1]");
  if (!(marking.min_fraction >= 0 && marking.min_fraction <= 1))
    throw std::invalid_argument("the minimum marked fraction must be in [0, 1]");
  if (!eta_squared.allFinite()) throw std::invalid_argument("an error indicator is not finite");
  std::vector<int> order(eta_squared.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return eta_squared[a] > eta_squared[b]; });
  if (order.empty()) return {};
  // Both strategies mark a prefix of `order`; count it.
  size_t count = 0;
  if (marking.strategy == Marking::Strategy::kDorfler) {
    const double goal = marking.theta * eta_squared.sum();
    double sum = 0;
    while (count < order.size() && (count == 0 || sum < goal)) sum += eta_squared[order[count++]];
  } else {
    // eta >= theta * max eta, compared squared (no square roots, the same set).
    const double bound = marking.theta * marking.theta * eta_squared[order.front()];
    while (count < order.size() && (count == 0 || eta_squared[order[count]] >= bound)) ++count;
  }
  const size_t at_least = static_cast<size_t>(std::ceil(marking.min_fraction * double(order.size())));
  order.resize(std::max(count, std::min(at_least, order.size())));
  return order;
}

std::vector<int> cells_of_marked_functions(const BezierMesh& mesh, const Eigen::VectorXd& eta_squared,
                                           const Marking& marking) {
  Eigen::VectorXd per_function = Eigen::VectorXd::Zero(mesh.num_functions());
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int f : mesh.functions(c)) per_function[f] += eta_squared[c];
  std::vector<char> marked(mesh.num_functions(), 0);
  for (int f : mark(per_function, marking)) marked[f] = 1;
  std::vector<int> cells;
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int f : mesh.functions(c))
      if (marked[f]) {
        cells.push_back(c);
        break;
      }
  return cells;
}

}  // namespace knotwork
