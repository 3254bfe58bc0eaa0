#pragma once
#include <Eigen/Core>

namespace knotwork {

// C = A B^T for the few-by-few matrices of one cell (univariate tables times extraction
// rows: 3 to 11 rows, a few dozen columns). At these sizes Eigen's blocked product spends
// its time packing and its lazy product strides through B; a plain loop with a contiguous
// inner index over the rows of C is several times faster.
inline void product_abt(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, Eigen::MatrixXd& C) {
  const Eigen::Index m = A.rows(), n = B.rows(), k = A.cols();
  C.setZero(m, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double* c = C.col(j).data();
    for (Eigen::Index l = 0; l < k; ++l) {
      const double b = B(j, l);
      const double* a = A.col(l).data();
      for (Eigen::Index i = 0; i < m; ++i) c[i] += a[i] * b;
    }
  }
}

}  // namespace knotwork
