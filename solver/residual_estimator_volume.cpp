// The residual estimator of residual_estimator.hpp on a volume's hexahedra. The terms are the
// planar ones with faces for edges:
//   eta_K^2 = h_K^2 ||f + div(A grad u_h) - c u_h||^2_K + 1/2 sum_F h_F ||[A grad u_h]||^2_F
//           + sum_{Neumann F} h_F ||g - (A grad u_h).n||^2_F + sum_{Nitsche F} h_F^-1 ||g - u_h||^2_F
// with h_K the cell's largest extent, h_F the diameter of the face piece. It is a pass of its
// own rather than a branch of the planar one because every geometric piece differs (a face
// rule and area element instead of an edge's, 3x3 Hessians, faces met through rectangles);
// what both share, the marking and the indicators' form, is residual_estimator.hpp's.
#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "quadrature/bernstein.hpp"
#include "quadrature/gauss_legendre.hpp"
#include "solver/cell_basis.hpp"
#include "solver/diffusion_at_points.hpp"
#include "solver/expression.hpp"
#include "solver/residual_estimator.hpp"

namespace knotwork {

namespace {

// The reference direction a face holds fixed and the order of its two free ones.
struct FaceFrame {
  int fixed, s, t;
  double at;
};
FaceFrame frame_of(CellSide side) {
  switch (side) {
    case kSideLeft: return {0, 1, 2, 0.0};
    case kSideRight: return {0, 1, 2, 1.0};
    case kSideBottom: return {1, 0, 2, 0.0};
    case kSideTop: return {1, 0, 2, 1.0};
    case kSideFront: return {2, 0, 1, 0.0};
    case kSideBack: return {2, 0, 1, 1.0};
  }
  throw std::logic_error("frame_of: not a side");
}

Eigen::Matrix3d jacobian_at(const GeometryAtPoints& g, Eigen::Index k) {
  Eigen::Matrix3d J;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) J(i, j) = g.jacobian(k, 3 * i + j);
  return J;
}

// A and c at points in space, with div A for div(A grad u) = A : Hess u + (div A) . grad u.
// One per thread (the evaluators are not thread-safe).
class VolumeCoefficients {
 public:
  VolumeCoefficients(const PoissonProblem& problem, const std::vector<ExactSolution>& derivatives)
      : a_(problem.coefficients.diffusion), constant_reaction_(problem.reaction) {
    for (const ExactSolution& d : derivatives) {
      d_.emplace_back();
      for (const Expression* e : {&d.u_x, &d.u_y, &d.u_z}) d_.back().emplace_back(*e);
    }
    if (!problem.coefficients.reaction.empty()) reaction_.emplace(problem.coefficients.reaction);
  }
  bool identity() const { return a_.identity(); }
  Eigen::Matrix3d A(const Eigen::Vector3d& x) { return a_(x[0], x[1], x[2]); }
  Eigen::Vector3d divergence(const Eigen::Vector3d& x) {
    if (d_.empty()) return Eigen::Vector3d::Zero();
    auto d = [&](int entry, int along) { return d_[entry][along](x[0], x[1], x[2]); };
    if (d_.size() == 1) return Eigen::Vector3d(d(0, 0), d(0, 1), d(0, 2));
    // Entries a11 a12 a13 a22 a23 a33: (div A)_j = sum_i d A_ij / d x_i.
    return Eigen::Vector3d(d(0, 0) + d(1, 1) + d(2, 2), d(1, 0) + d(3, 1) + d(4, 2), d(2, 0) + d(4, 1) + d(5, 2));
  }
  double reaction(const Eigen::Vector3d& x) { return reaction_ ? (*reaction_)(x[0], x[1], x[2]) : constant_reaction_; }

 private:
  DiffusionAtPoints a_;
  std::vector<std::vector<ExpressionEvaluator>> d_;  // per entry of A: its x, y and z derivatives
  std::optional<ExpressionEvaluator> reaction_;
  double constant_reaction_;
};

// u_h's Bernstein coefficients on a cell.
void bernstein_of(const BezierMesh& mesh, int c, const Eigen::MatrixXd& C, const Eigen::VectorXd& coefficients,
                  Eigen::VectorXd& local, Eigen::VectorXd& beta) {
  const auto ids = mesh.functions(c);
  local.resize(static_cast<Eigen::Index>(ids.size()));
  for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
  beta.noalias() = C.transpose() * local;
}

// h_K^2 ||f + div(A grad u_h) - c u_h||^2_K on cell c.
double interior_residual(const BezierMesh& mesh, const GeometryMap& geometry, const Eigen::VectorXd& coefficients,
                         int c, ExpressionBatch& f, VolumeCoefficients& coefficient) {
  const BezierCell& cell = mesh.cell(c);
  const int nu = cell.degree_u + 2, nv = cell.degree_v + 2, nw = cell.degree_w + 2;
  const BernsteinTable& table = bernstein_table(cell.degree_u, cell.degree_v, cell.degree_w, nu, nv, nw);
  thread_local Eigen::MatrixXd second_ref[6], second_map;
  thread_local GeometryAtPoints g, middles;
  thread_local Eigen::VectorXd local, beta, U, grad_ref[3], hess_ref[6];
  // The second derivatives of the Bernstein polynomials at this rule: kept while the degrees stay.
  thread_local int kept[3] = {-1, -1, -1};
  if (kept[0] != cell.degree_u || kept[1] != cell.degree_v || kept[2] != cell.degree_w) {
    tensor_bernstein_second(cell.degree_u, cell.degree_v, cell.degree_w, table.point_u, table.point_v, table.point_w,
                            second_ref);
    kept[0] = cell.degree_u, kept[1] = cell.degree_v, kept[2] = cell.degree_w;
  }
  geometry.volume_second_derivatives(c, table.point_u, table.point_v, table.point_w, second_map, &g);  // and x, J
  bernstein_of(mesh, c, mesh.extraction(c), coefficients, local, beta);
  U.noalias() = table.value * beta;
  grad_ref[0].noalias() = table.d_u * beta;
  grad_ref[1].noalias() = table.d_v * beta;
  grad_ref[2].noalias() = table.d_w * beta;
  for (int k = 0; k < 6; ++k) hess_ref[k].noalias() = second_ref[k] * beta;
  const int n = table.num_points();
  f.evaluate(g.x.col(0).data(), g.x.col(1).data(), g.x.col(2).data(), n);
  const double* source = f.result(0);
  static constexpr int kPair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};  // (a, b) -> uu uv uw vv vw ww
  double integral = 0;
  for (int k = 0; k < n; ++k) {
    // grad = J^-T grad_ref; Hess_ref = J^T Hess J + sum_i (d u / d x_i) Hess_ref(x_i).
    const Eigen::Matrix3d J = jacobian_at(g, k);
    const Eigen::Matrix3d Jinv = J.inverse();
    const Eigen::Vector3d grad = Jinv.transpose() * Eigen::Vector3d(grad_ref[0][k], grad_ref[1][k], grad_ref[2][k]);
    Eigen::Matrix3d H;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        H(a, b) = hess_ref[kPair[a][b]][k];
        for (int i = 0; i < 3; ++i) H(a, b) -= grad[i] * second_map(k, 6 * i + kPair[a][b]);
      }
    const Eigen::Matrix3d hessian = Jinv.transpose() * H * Jinv;
    const Eigen::Vector3d x = g.x.row(k).transpose();
    const double divergence = coefficient.identity() ? hessian.trace()
                                                     : (coefficient.A(x).cwiseProduct(hessian)).sum() + coefficient.divergence(x).dot(grad);
    const double r = source[k] + divergence - coefficient.reaction(x) * U[k];
    integral += table.weight[k] * std::abs(J.determinant()) * r * r;
  }
  // h_K: the largest distance between the midpoints of opposite faces.
  Eigen::VectorXd mu(6), mv(6), mw(6);
  mu << 0, 1, 0.5, 0.5, 0.5, 0.5;
  mv << 0.5, 0.5, 0, 1, 0.5, 0.5;
  mw << 0.5, 0.5, 0.5, 0.5, 0, 1;
  geometry.evaluate_volume(c, mu, mv, mw, middles);
  double h = 0;
  for (int d = 0; d < 3; ++d) h = std::max(h, (middles.x.row(2 * d + 1) - middles.x.row(2 * d)).norm());
  return h * h * integral;
}

// The cell reference points of the n x n Gauss points of a face piece, and their weights.
void face_points(CellSide side, double s0, double s1, double t0, double t1, bool transposed, const QuadratureRule1D& rule,
                 Eigen::VectorXd (&at)[3]) {
  const FaceFrame f = frame_of(side);
  const int n = static_cast<int>(rule.nodes.size());
  for (Eigen::VectorXd& a : at) a.resize(n * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int k = i + n * j;
      const double alpha = transposed ? rule.nodes[j] : rule.nodes[i], beta = transposed ? rule.nodes[i] : rule.nodes[j];
      at[f.fixed][k] = f.at;
      at[f.s][k] = s0 + alpha * (s1 - s0);
      at[f.t][k] = t0 + beta * (t1 - t0);
    }
}

// The physical diameter of a face piece: its longer diagonal.
double piece_diameter(const GeometryMap& geometry, int c, CellSide side, double s0, double s1, double t0, double t1) {
  const FaceFrame f = frame_of(side);
  Eigen::VectorXd at[3] = {Eigen::VectorXd(4), Eigen::VectorXd(4), Eigen::VectorXd(4)};
  const double s[4] = {s0, s1, s0, s1}, t[4] = {t0, t1, t1, t0};
  for (int k = 0; k < 4; ++k) at[f.fixed][k] = f.at, at[f.s][k] = s[k], at[f.t][k] = t[k];
  GeometryAtPoints g;
  geometry.evaluate_volume(c, at[0], at[1], at[2], g);
  return std::max((g.x.row(1) - g.x.row(0)).norm(), (g.x.row(3) - g.x.row(2)).norm());
}

}  // namespace

ErrorIndicators volume_residual_indicators(const BezierMesh& mesh, const GeometryMap& geometry,
                                           const Eigen::VectorXd& coefficients, const PoissonProblem& problem) {
  if (mesh.is_rational()) throw std::invalid_argument("the residual estimator needs a polynomial (non-rational) space");
  if (!mesh.has_interfaces())
    throw std::invalid_argument("the residual estimator needs the mesh's cell interfaces, and this family gives none");
  {
    Eigen::MatrixXd probe;
    const Eigen::VectorXd half = Eigen::VectorXd::Constant(1, 0.5);
    if (mesh.num_cells() == 0 || !geometry.volume_second_derivatives(0, half, half, half, probe))
      throw std::invalid_argument("the residual estimator needs a geometry map with second derivatives");
  }
  if (!problem.coefficients.diffusion.empty() && problem.coefficients.diffusion.size() != 1 &&
      problem.coefficients.diffusion.size() != 6)
    throw std::invalid_argument("the residual estimator on a volume takes a scalar coefficient or a 3x3 matrix");
  ErrorIndicators ind;
  ind.eta_squared = Eigen::VectorXd::Zero(mesh.num_cells());
  std::vector<ExactSolution> diffusion;  // derivatives of A's entries, once (GiNaC is not thread-safe)
  for (const Expression& a : problem.coefficients.diffusion) diffusion.push_back(differentiate_volume_solution(a));
  const ExpressionBatch compiled_source({problem.source});
#pragma omp parallel
  {
    ExpressionBatch f(compiled_source);
    VolumeCoefficients coefficient(problem, diffusion);
#pragma omp for schedule(dynamic, 16)
    for (int c = 0; c < mesh.num_cells(); ++c)
      ind.eta_squared[c] = interior_residual(mesh, geometry, coefficients, c, f, coefficient);
  }
  for (int c = 0; c < mesh.num_cells(); ++c) ind.residual_part += ind.eta_squared[c];  // in cell order: no thread order
  // Jumps of the flux across interior face pieces, half to each neighbour.
  const std::vector<CellInterface>& pieces = mesh.interfaces();
  std::vector<double> piece_value(pieces.size()), piece_max(pieces.size());
#pragma omp parallel
  {
    CellBasis ca, cb;
    Eigen::VectorXd at_a[3], at_b[3], local, beta_a, beta_b;
    VolumeCoefficients coefficient(problem, diffusion);
    QuadratureRule1D rule;  // made again only when the number of points changes
#pragma omp for schedule(dynamic, 64)
    for (size_t s = 0; s < pieces.size(); ++s) {
      const CellInterface& e = pieces[s];
      const BezierCell& a = mesh.cell(e.cell_a);
      const int n = std::max({a.degree_u, a.degree_v, int(a.degree_w)}) + 2;
      if (static_cast<int>(rule.nodes.size()) != n) rule = gauss_legendre(n);
      face_points(e.side_a, e.a_from, e.a_to, e.a_from_t, e.a_to_t, false, rule, at_a);
      face_points(e.side_b, e.b_from, e.b_to, e.b_from_t, e.b_to_t, e.transposed, rule, at_b);
      evaluate_volume_cell_basis_at(mesh, geometry, e.cell_a, at_a[0], at_a[1], at_a[2], ca);
      evaluate_volume_cell_basis_at(mesh, geometry, e.cell_b, at_b[0], at_b[1], at_b[2], cb);
      bernstein_of(mesh, e.cell_a, ca.C, coefficients, local, beta_a);
      bernstein_of(mesh, e.cell_b, cb.C, coefficients, local, beta_b);
      const FaceFrame fa = frame_of(e.side_a);
      const double piece = std::abs((e.a_to - e.a_from) * (e.a_to_t - e.a_from_t));  // its share of a's face
      double integral = 0, biggest = 0;
      for (int k = 0; k < n * n; ++k) {
        Eigen::Vector3d step;
        for (int d = 0; d < 3; ++d) step[d] = ca.grad(d).row(k).dot(beta_a) - cb.grad(d).row(k).dot(beta_b);
        const Eigen::Vector3d x = ca.geometry.x.row(k).transpose();
        const double jump = coefficient.identity() ? step.norm() : (coefficient.A(x) * step).norm();
        const Eigen::Matrix3d J = jacobian_at(ca.geometry, k);
        const double area = J.col(fa.s).cross(J.col(fa.t)).norm() * piece * rule.weights[k % n] * rule.weights[k / n];
        integral += area * jump * jump;
        biggest = std::max(biggest, jump);
      }
      const double h = piece_diameter(geometry, e.cell_a, e.side_a, e.a_from, e.a_to, e.a_from_t, e.a_to_t);
      piece_value[s] = 0.5 * h * integral;
      piece_max[s] = biggest;
    }
  }
  for (size_t s = 0; s < pieces.size(); ++s) {
    ind.eta_squared[pieces[s].cell_a] += piece_value[s];
    ind.eta_squared[pieces[s].cell_b] += piece_value[s];
    ind.jump_part += 2 * piece_value[s];
    ind.max_gradient_jump = std::max(ind.max_gradient_jump, piece_max[s]);
  }
  // Boundary faces: Neumann h_F ||g - (A grad u_h).n||^2, Dirichlet by Nitsche ||g - u_h||^2 / h_F.
  VolumeCoefficients coefficient(problem, diffusion);
  CellBasis fb;
  Eigen::VectorXd local, beta;
  // Per boundary condition, its data's evaluators, made on its first face: g, or h, or a flux
  // vector F (h = F.n), or grad u of the exact solution.
  std::vector<std::optional<std::vector<ExpressionEvaluator>>> evaluators(problem.boundary.size());
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    for (int side = 0; side < 6; ++side) {
      const int id = cell.boundary[side];
      if (id < 0 || id >= static_cast<int>(problem.boundary.size())) continue;
      const BoundaryCondition& bc = problem.boundary[id];
      const bool weak_dirichlet = bc.kind == BoundaryKind::kDirichlet && problem.dirichlet_method == DirichletMethod::kNitsche;
      if (bc.kind != BoundaryKind::kNeumann && !weak_dirichlet) continue;
      if (bc.from_exact && !problem.exact) throw std::invalid_argument("boundary data come from the exact solution, but none is given");
      const int n = std::max({cell.degree_u, cell.degree_v, int(cell.degree_w)}) + 2;
      evaluate_side_basis(mesh, geometry, c, CellSide(side), n, fb);
      bernstein_of(mesh, c, fb.C, coefficients, local, beta);
      const bool flux_data = !weak_dirichlet && !bc.from_exact && !bc.flux.empty();
      if (!evaluators[id]) {
        std::vector<ExpressionEvaluator>& made = evaluators[id].emplace();
        if (weak_dirichlet) made.emplace_back(bc.from_exact ? problem.exact->u : bc.value);
        else if (bc.from_exact) for (const Expression* d : {&problem.exact->u_x, &problem.exact->u_y, &problem.exact->u_z}) made.emplace_back(*d);
        else if (flux_data) for (const Expression& d : bc.flux) made.emplace_back(d);
        else made.emplace_back(bc.value);
        if (!weak_dirichlet && (bc.from_exact || flux_data) && made.size() != 3)
          throw std::invalid_argument("Neumann data on a volume's face need three flux components");
      }
      std::vector<ExpressionEvaluator>& data = *evaluators[id];
      double integral = 0;
      for (int k = 0; k < fb.measure.size(); ++k) {
        const Eigen::Vector3d x = fb.geometry.x.row(k).transpose();
        const Eigen::Vector3d normal = fb.normal.row(k).transpose();
        double r;
        if (weak_dirichlet) {
          r = data[0](x[0], x[1], x[2]) - fb.value.row(k).dot(beta);
        } else {
          const Eigen::Matrix3d A = coefficient.A(x);
          Eigen::Vector3d grad;
          for (int d = 0; d < 3; ++d) grad[d] = fb.grad(d).row(k).dot(beta);
          double g;
          if (data.size() == 3) {
            const Eigen::Vector3d v(data[0](x[0], x[1], x[2]), data[1](x[0], x[1], x[2]), data[2](x[0], x[1], x[2]));
            g = (bc.from_exact ? Eigen::Vector3d(A * v) : v).dot(normal);
          } else {
            g = data[0](x[0], x[1], x[2]);
          }
          r = g - (A * grad).dot(normal);
        }
        integral += fb.measure[k] * r * r;
      }
      const double h = piece_diameter(geometry, c, CellSide(side), 0, 1, 0, 1);
      const double term = weak_dirichlet ? integral / h : h * integral;
      ind.eta_squared[c] += term;
      (weak_dirichlet ? ind.dirichlet_part : ind.neumann_part) += term;
    }
  }
  return ind;
}

}  // namespace knotwork
