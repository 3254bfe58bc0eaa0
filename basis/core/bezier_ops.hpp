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
}  // namespace knotwork
