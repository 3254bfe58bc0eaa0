#include "solver/surface_source.hpp"

#include <Eigen/Dense>

namespace knotwork {

double tangential_divergence(const SurfaceFrame& s, const Eigen::Vector3d& g, const Eigen::Matrix3d& H,
                             const Eigen::Matrix3d& A, const Eigen::Matrix3d dA[3]) {
  // w = P A P g; div_G w = G^{ab} x_a . d_b w, with d_b the derivative along parameter b:
  //   d_b w = P_b A P g + P (d_b A) P g + P A P_b g + P A P H x_b,
  //   P_b = -(n_b n^T + n n_b^T),  n_b = P d_b(x_u x x_v) / |x_u x x_v|,  d_b A = sum_k dA_k (x_b)_k.
  const Eigen::Vector3d N = s.xu.cross(s.xv);
  const double area = N.norm();
  const Eigen::Vector3d n = N / area;
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - n * n.transpose();
  const Eigen::Vector3d x_b[2] = {s.xu, s.xv};
  const Eigen::Vector3d n_b[2] = {P * (s.xuu.cross(s.xv) + s.xu.cross(s.xuv)) / area,
                                  P * (s.xuv.cross(s.xv) + s.xu.cross(s.xvv)) / area};
  Eigen::Matrix2d G;
  G << s.xu.dot(s.xu), s.xu.dot(s.xv), s.xu.dot(s.xv), s.xv.dot(s.xv);
  const Eigen::Matrix2d Gi = G.inverse();
  const Eigen::Vector3d Pg = P * g;
  double divergence = 0;
  for (int b = 0; b < 2; ++b) {
    const Eigen::Matrix3d P_b = -(n_b[b] * n.transpose() + n * n_b[b].transpose());
    const Eigen::Matrix3d A_b = dA[0] * x_b[b](0) + dA[1] * x_b[b](1) + dA[2] * x_b[b](2);
    const Eigen::Vector3d w_b = P_b * (A * Pg) + P * (A_b * Pg) + P * (A * (P_b * g)) + P * (A * (P * (H * x_b[b])));
    for (int a = 0; a < 2; ++a) divergence += Gi(a, b) * x_b[a].dot(w_b);
  }
  return divergence;
}

DerivedSurfaceSource::DerivedSurfaceSource(const ExactSolution& u, const std::vector<ExactSolution>& coefficient,
                                           const Expression* variable_reaction, double reaction)
    : value_(u.u), entries_(static_cast<int>(coefficient.size())), reaction_(reaction) {
  for (const Expression* e : {&u.u_x, &u.u_y, &u.u_z}) gradient_.emplace_back(*e);
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) hessian_.emplace_back(u.hessian[i][j]);
  for (const ExactSolution& a : coefficient)
    for (const Expression* t : {&a.u, &a.u_x, &a.u_y, &a.u_z}) coefficient_.emplace_back(*t);
  if (variable_reaction) variable_reaction_.emplace(*variable_reaction);
}

void DerivedSurfaceSource::operator()(const Eigen::MatrixXd& x, const Eigen::MatrixXd& J,
                                      const Eigen::MatrixXd& second, Eigen::VectorXd& out) {
  out.resize(x.rows());
  for (Eigen::Index q = 0; q < x.rows(); ++q) {
    const SurfaceFrame s{{J(q, 0), J(q, 2), J(q, 4)},
                         {J(q, 1), J(q, 3), J(q, 5)},
                         {second(q, 0), second(q, 3), second(q, 6)},
                         {second(q, 1), second(q, 4), second(q, 7)},
                         {second(q, 2), second(q, 5), second(q, 8)}};
    const double px = x(q, 0), py = x(q, 1), pz = x(q, 2);
    Eigen::Vector3d g;
    Eigen::Matrix3d H;
    for (int i = 0, h = 0; i < 3; ++i) {
      g(i) = gradient_[i](px, py, pz);
      for (int j = i; j < 3; ++j, ++h) H(i, j) = H(j, i) = hessian_[h](px, py, pz);
    }
    double diffusion;
    if (entries_ == 6) {
      // The matrix field and its partial derivatives, from the upper triangle a11 a12 a13 a22 a23 a33.
      Eigen::Matrix3d A, dA[3];
      const int row[6] = {0, 0, 0, 1, 1, 2}, col[6] = {0, 1, 2, 1, 2, 2};
      for (int e = 0; e < 6; ++e) {
        A(row[e], col[e]) = A(col[e], row[e]) = coefficient_[4 * e](px, py, pz);
        for (int k = 0; k < 3; ++k)
          dA[k](row[e], col[e]) = dA[k](col[e], row[e]) = coefficient_[4 * e + 1 + k](px, py, pz);
      }
      diffusion = -tangential_divergence(s, g, H, A, dA);
    } else {
      // The Laplace-Beltrami operator in the curvature form (kappa = -G^{ij} x_ij . n, the sum
      // of the principal curvatures): what tangential_divergence gives for A = I.
      Eigen::Matrix2d G;
      G << s.xu.dot(s.xu), s.xu.dot(s.xv), s.xu.dot(s.xv), s.xv.dot(s.xv);
      const Eigen::Matrix2d Gi = G.inverse();
      const Eigen::Vector3d n = s.xu.cross(s.xv).normalized();
      const double kappa = -(Gi(0, 0) * s.xuu.dot(n) + 2 * Gi(0, 1) * s.xuv.dot(n) + Gi(1, 1) * s.xvv.dot(n));
      const double laplace_beltrami = H.trace() - n.dot(H * n) - kappa * g.dot(n);
      diffusion = -laplace_beltrami;
      if (entries_ == 1) {
        const Eigen::Vector3d grad_a(coefficient_[1](px, py, pz), coefficient_[2](px, py, pz), coefficient_[3](px, py, pz));
        diffusion = -coefficient_[0](px, py, pz) * laplace_beltrami - grad_a.dot(g - g.dot(n) * n);
      }
    }
    const double c = variable_reaction_ ? (*variable_reaction_)(px, py, pz) : reaction_;
    out[q] = diffusion + (c != 0 ? c * value_(px, py, pz) : 0.0);
  }
}

}  // namespace knotwork
