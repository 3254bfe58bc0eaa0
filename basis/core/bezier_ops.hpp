#pragma once
#include <Eigen/Core>

namespace knotwork {

// Bernstein change-of-basis matrices on [0,1], written for coefficient vectors.
// A polynomial with Bernstein coefficients beta on [0,1] has coefficients
// subdivision_matrix(p, s, t) * beta on the sub-interval [s, t].
Eigen::MatrixXd subdivision_matrix(int p, double s, double t);
// ... and degree_elevation_matrix(p, r) * beta as a polynomial of degree p+r.
Eigen::MatrixXd degree_elevation_matrix(int p, int r);

}  // namespace knotwork

namespace knotwork {
// Inverse of the collocation matrix of the tensor Bernstein basis of bi-degree (p, q)
// at the equispaced nodes (i/p, j/q), node index i + (p+1) j. Multiplying it with
// values at those nodes gives the Bernstein coefficients of the interpolant.
Eigen::MatrixXd bernstein_interpolation_inverse(int p, int q);
// The same in three directions, applied direction by direction (the univariate inverses, not a
// dense ((p+1)(q+1)(r+1))^2 one): the Bernstein coefficients of the interpolant of degrees
// (p, q, r) of the values at the nodes (i/p, j/q, k/r), node i + (p+1) (j + (q+1) k), column
// by column of `values`.
Eigen::MatrixXd bernstein_interpolant(int p, int q, int r, const Eigen::MatrixXd& values);
}  // namespace knotwork
