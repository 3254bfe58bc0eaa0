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

// Second reference derivatives of the same polynomials at the same points (u_uu, u_uv, v_vv),
// for the curvature of surfaces and the Hessian of maps.
void tensor_bernstein_second(int p, int q, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                             Eigen::MatrixXd& d_uu, Eigen::MatrixXd& d_uv, Eigen::MatrixXd& d_vv);

// Tabulated tensor-product Bernstein basis of bi-degree (p, q) at the tensor
// Gauss points of a (nu x nv)-point rule on [0,1]^2.
// Point index k = i + nu*j (i along u); function index b = a + (p+1)*c (a along u).
struct BernsteinTable {
  int p = 0, q = 0;
  QuadratureRule1D rule_u, rule_v;
  Eigen::VectorXd point_u, point_v;  // reference coordinates of each tensor point
  Eigen::VectorXd weight;            // tensor quadrature weight of each point (sum 1)
  Eigen::MatrixXd value;             // points x functions
  Eigen::MatrixXd d_u, d_v;          // derivatives with respect to the reference u, v
  int num_points() const { return static_cast<int>(weight.size()); }
  int num_functions() const { return (p + 1) * (q + 1); }
};

// Computed once per (p, q, nu, nv) and kept for the life of the program;
// thread-safe. The returned reference stays valid.
const BernsteinTable& bernstein_table(int p, int q, int nu, int nv);

}  // namespace knotwork
