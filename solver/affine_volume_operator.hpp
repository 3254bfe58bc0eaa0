#pragma once
// The Poisson operator of a trivariate B-spline space whose map is one affine map
// x = x0 + J (u, v, w): in parameter coordinates the form is constant,
//   K = sum_ab G_ab prod_d I_d^ab + r M_u (x) M_v (x) M_w,  G = s |det J| (J^T J)^{-1},  r = c |det J|,
// where I_d^ab is the direction's stiffness K_d (a = b = d), its mixed matrix D_d (derivative on
// the row's function, a = d != b) or its transpose (b = d != a), and its mass M_d otherwise. The
// univariate matrices are integrated by the assembly's Gauss rules, exact for them, so K is the
// element loop's matrix up to rounding (tests/test_affine_volume_operator.cpp), written straight
// into CHOLMOD's layout with O(1) work per entry, where the element loop forms (p+1)^6 products
// per hexahedron. The load is summed one direction at a time; the operator applies itself by
// mode products (the lifting of Dirichlet values). Written here: no library on this machine
// assembles spline matrices.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "solver/matrix_free.hpp"

namespace knotwork {

class AffineVolumeOperator final : public MatrixFreePoisson {
 public:
  // Functions i + n_u j + n_u n_v k of space[0] x space[1] x space[2]. points[d]: Gauss points per
  // element along d (0: degree + 1, the assembly's default). Throws std::invalid_argument where
  // det J <= 0 or a degree is above 15.
  // error_points_w: the error rule's points along w (0: degree + 2), which squared_errors, whose
  // interface names u and v only, takes from here.
  AffineVolumeOperator(const std::array<BSplineBasis1D, 3>& space, const AffineVolumeMap& map, double stiffness,
                       double reaction, std::array<int, 3> points = {0, 0, 0}, int error_points_w = 0);

  int num_functions() const override { return n_[0] * n_[1] * n_[2]; }
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override;
  // Where the free functions are a box numbered as one (a + count0 (b + count1 c)): the
  // Dirichlet faces' functions fixed, as on a box with Dirichlet and Neumann faces.
  bool applies_free(const DofLayout& layout) const override;
  void apply_free(const DofLayout& layout, const Eigen::VectorXd& x, Eigen::VectorXd& y) const override;
  Eigen::VectorXd diagonal() const override;
  // F_a = int f R_a by the same rules; throws InputError naming the first cell (in the mesh's
  // order) where f is not finite, as the element loop does.
  Eigen::VectorXd load(const Expression& source) const override;
  int max_row_nonzeros() const override;
  // The squared L2 and H1-seminorm errors of u_h against the exact solution (of x, y, z) by
  // points_u x points_v x error_points_w Gauss points per hexahedron (0: degree + 2, as
  // error_norms), u_h and its gradient summed one direction at a time from the coefficients (no
  // mesh), J^-T constant; per cell (eu + n_eu (ev + n_ev ew), the mesh's order) when asked; over
  // `cells` only.
  bool squared_errors(const Eigen::VectorXd& coefficients, const ExactSolution& exact, int points_u, int points_v,
                      std::array<double, 2>& squares, Eigen::VectorXd* h1_per_cell, CellRange cells = {}) const override;
  bool all_elements_affine() const override { return true; }
  bool assembles_lower() const override { return true; }
  bool writes_rows() const override { return true; }
  Eigen::SparseMatrix<double> lower_matrix(const DofLayout& layout) const override;
  void row_entries(int row, int count, const int* columns, double* values) const override;
  bool gives_pattern() const override { return true; }
  Eigen::SparseMatrix<double> lower_pattern(const DofLayout& layout) const override;
  void coupled_functions(int function, std::vector<int>& out) const override;

  // For the volume multigrid without a matrix (solver/tensor_multigrid_3d.hpp).
  // A box of functions: first[d] .. first[d] + count[d] - 1 per direction, numbered
  // a + count[0] (b + count[1] c) from its corner.
  struct FunctionBox {
    std::array<int, 3> first{}, count{};
    long size() const { return long(count[0]) * count[1] * count[2]; }
  };
  // The same form on other (coarser) spaces: on an affine map the rediscretized operator is the
  // Galerkin one of nested spaces, both integrated exactly.
  std::shared_ptr<const AffineVolumeOperator> on_spaces(const std::array<BSplineBasis1D, 3>& space) const;
  // out = (K x) over the functions of `rows`, in its numbering, for x over the box `free` (zero
  // outside it) with rows inside free: by mode products over the rows' reach, serially (for a
  // smoother's block).
  void apply_box(const double* x, const FunctionBox& free, const FunctionBox& rows, double* out) const;
  // out = (K x) over all of `free`, threaded over slabs along w.
  void apply_within(const double* x, const FunctionBox& free, double* out) const;
  const std::array<BSplineBasis1D, 3>& spaces() const { return space_; }
  double reaction() const { return reaction_; }

 private:
  // One direction: its rule's tables per element and its univariate matrices as bands (entry
  // (a, c) at a (2p + 1) + c - a + p), and per function the range of functions it shares an
  // element with.
  struct Direction {
    int degree = 0, points = 0, elements = 0;
    std::vector<int> first;                     // per element, its first function
    std::vector<double> value, derivative;      // per element, point-major, the p + 1 functions
    std::vector<double> node, weight;           // per element, the points and weights times the length
    std::vector<double> K, M, D;                // bands: stiffness, mass, mixed (derivative on the row's function)
    std::vector<int> low, high;                 // reach
  };
  // `matrices` false: the rule's tables and the reach only (an error rule's).
  static Direction direction(const BSplineBasis1D& space, int points, bool matrices = true);
  // The physical points of element (eu, ev, ew) under the rules of U, V, W (point a + Qu (b + Qv c)).
  void element_points(const Direction& U, const Direction& V, const Direction& W, int eu, int ev, int ew, double* x,
                      double* y, double* z) const;
  double entry(int i, int j, int k, int i0, int j0, int k0) const;
  // The box from its first and last free functions (what applies_free checked).
  FunctionBox free_box(const DofLayout& layout) const;
  Eigen::SparseMatrix<double> write_lower(const DofLayout& layout, bool values) const;

  std::array<Direction, 3> d_;
  std::array<BSplineBasis1D, 3> space_;  // for the error rule's tables and on_spaces
  double stiffness_ = 1, reaction_ = 0;  // as given, for on_spaces
  std::array<int, 3> points_{};
  int error_points_w_ = 0;
  std::array<int, 3> n_{};
  std::array<std::vector<double>, 3> ends_;  // per direction, the elements' ends (breakpoints)
  AffineVolumeMap map_;
  double g_[3][3] = {};  // s |det J| (J^T J)^{-1}
  double r_ = 0;         // c |det J|
  double det_ = 0;
};

}  // namespace knotwork
