#pragma once
// Extreme eigenvalues of a Jacobi-scaled SPD matrix, D^{-1/2} A D^{-1/2} with D = diag(A):
// how well conditioned a basis is, independent of how its functions are scaled. Lanczos
// (Spectra, a Debian package) on the matrix for the largest, on its inverse (CHOLMOD) for
// the smallest: linear memory, no dense eigensolver at any size.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>

namespace knotwork {

struct SpectrumEstimate {
  double smallest = 0, largest = 0;  // of D^{-1/2} A D^{-1/2}
  bool computed = false;
  std::string failure;  // why not (Lanczos did not converge, A numerically singular, ...)
  // The eigenvector of the smallest eigenvalue, in A's unknowns (D^{-1/2} times the scaled
  // matrix's eigenvector), when asked for: which functions carry it.
  Eigen::VectorXd smallest_vector;
  double condition() const { return computed && smallest > 0 ? largest / smallest : 0; }
};

// A given by its lower triangle (as the assembly stores it). Relative accuracy about 1e-6
// in each eigenvalue; a matrix of fewer than 3 unknowns is done densely.
SpectrumEstimate jacobi_scaled_spectrum(const Eigen::SparseMatrix<double>& lower, bool want_vector = false);

}  // namespace knotwork
