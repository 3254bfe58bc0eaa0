#pragma once
#include <Eigen/Core>

#include "quadrature/gauss_legendre.hpp"

namespace knotwork {

// Values (row 0) and first derivatives (row 1) of the p+1 Bernstein polynomials
// of degree p on [0,1] at t: out is 2 x (p+1).
void bernstein_values_and_derivatives(int p, double t, double* values, double* derivatives);

// Tensor-product Bernstein polynomials of bi-degree (p, q) and their reference
// derivatives at arbitrary points (u_k, v_k): points x functions, function a + (p+1) c.
void tensor_bernstein(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                      Eigen::MatrixXd& value, Eigen::MatrixXd& d_u, Eigen::MatrixXd& d_v);

// Trivariate, degrees (p, q, r), at points (u_k, v_k, w_k): function a + (p+1) b + (p+1)(q+1) c.
void tensor_bernstein(int p, int q, int r, const Eigen::VectorXd& u, const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                      Eigen::MatrixXd& value, Eigen::MatrixXd& d_u, Eigen::MatrixXd& d_v, Eigen::MatrixXd& d_w);

// Second reference derivatives of the same polynomials at the same points (u_uu, u_uv, v_vv),
// for the curvature of surfaces and the Hessian of maps.
void tensor_bernstein_second(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                             Eigen::MatrixXd& d_uu, Eigen::MatrixXd& d_uv, Eigen::MatrixXd& d_vv);
// Trivariate: second[0..5] = d_uu, d_uv, d_uw, d_vv, d_vw, d_ww (the residual estimator on hexahedra).
void tensor_bernstein_second(int p, int q, int r, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                             const Eigen::VectorXd& w, Eigen::MatrixXd (&second)[6]);

// Tabulated tensor-product Bernstein basis of bi-degree (p, q) at the tensor Gauss points of a
// (nu x nv)-point rule on [0,1]^2, or of degrees (p, q, r) at those of a (nu x nv x nw) rule on
// [0,1]^3 (a volume's cells; r = 0 and no w data in 2D).
// Point index k = i + nu*j [+ nu*nv*l] (i along u); function index b = a + (p+1)*c [+ (p+1)(q+1) e].
struct BernsteinTable {
  int p = 0, q = 0, r = 0;
  QuadratureRule1D rule_u, rule_v, rule_w;
  Eigen::VectorXd point_u, point_v, point_w;  // reference coordinates of each tensor point
  Eigen::VectorXd weight;                     // tensor quadrature weight of each point (sum 1)
  Eigen::MatrixXd value;                      // points x functions
  Eigen::MatrixXd d_u, d_v, d_w;              // derivatives with respect to the reference u, v, w
  int num_points() const { return static_cast<int>(weight.size()); }
  int num_functions() const { return (p + 1) * (q + 1) * (r + 1); }
};

// Computed once per (p, q, nu, nv) [or (p, q, r, nu, nv, nw)] and kept for the life of the
// program; thread-safe. The returned reference stays valid.
const BernsteinTable& bernstein_table(int p, int q, int nu, int nv);
const BernsteinTable& bernstein_table(int p, int q, int r, int nu, int nv, int nw);

}  // namespace knotwork
