#pragma once
// The Poisson operator of a tensor-product spline space on one patch, applied without a
// matrix: y = K x by sum factorization, element by element (docs/SOLVERS.md, "Without a
// matrix"). Written here because no library on this machine (Eigen, PETSc, hypre) evaluates
// spline spaces; the small contractions are plain loops, as in solver/separable_cells.cpp.
//
// K_ab = c_s int grad R_a . grad R_b + c_r int R_a R_b over the patch, R_a = w_a N_a / W the
// space's functions (W = sum w_a N_a; w = 1 for B-splines), with Gauss rules of the
// assembly's size. Per element the solution's values and parameter gradients at the points
// come from one direction at a time (O(p^3) flops per element, not the O(p^4) of an element
// matrix), and so do the geometry's, from its homogeneous control net: nothing is stored per
// point, so the operator needs O(n_u + n_v) memory besides the vectors.
#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cstddef>
#include <vector>

#include "basis/core/bspline_basis.hpp"
#include "solver/matrix_free.hpp"

namespace knotwork {

// What the operator reads of a tensor space: its univariate bases (function i + n_u j), its
// weights per function (empty: B-splines), and the geometry as a spline over the same elements
// in homogeneous form (w x, w y, w), control point i + n_u^g j of geometry_u x geometry_v.
struct TensorPatch {
  const BSplineBasis1D* space_u = nullptr;
  const BSplineBasis1D* space_v = nullptr;
  const Eigen::VectorXd* weights = nullptr;
  const BSplineBasis1D* geometry_u = nullptr;
  const BSplineBasis1D* geometry_v = nullptr;
  const Eigen::MatrixX3d* geometry = nullptr;
  // True when `geometry` outlives the operator (a space's own net): the operator then reads it
  // in place where it needs no scaling (weights 1), instead of copying 24 bytes per function.
  bool geometry_outlives_operator = false;
};

class TensorPoissonOperator final : public MatrixFreePoisson {
 public:
  // points_u, points_v: Gauss points per element and direction (0: degree + 1, the assembly's
  // default). Throws std::invalid_argument for degrees above kMaxDegree, bases whose
  // elements differ, or a net of the wrong size.
  TensorPoissonOperator(const TensorPatch& patch, double stiffness, double reaction, int points_u = 0,
                        int points_v = 0);
  // (Not copied: it may point into itself.)
  TensorPoissonOperator(const TensorPoissonOperator&) = delete;
  TensorPoissonOperator& operator=(const TensorPoissonOperator&) = delete;
  static constexpr int kMaxDegree = 15;

  int num_functions() const override { return n_u_ * n_v_; }
  // y = K x over all functions (threaded over bands of element rows; y is overwritten).
  void apply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const override;
  // K's diagonal, by the same quadrature (one pass, O(p^2) per point). Throws
  // std::invalid_argument where det J <= 0 at a point.
  Eigen::VectorXd diagonal() const override;
  // int f R_a by the same rule, f evaluated at each element's points in one batch.
  Eigen::VectorXd load(const Expression& source) const override;
  int max_row_nonzeros() const override { return (2 * u_.degree + 1) * (2 * v_.degree + 1); }
  // By points_u x points_v Gauss points per element (0: degree + 2), the values and gradients
  // of u_h one direction at a time; per element (eu + n_eu ev) in h1_per_element, the cell
  // numbering of the space's mesh (also a part's: its element rows from its first). False for
  // an operator made without a geometry net.
  bool squared_errors(const Eigen::VectorXd& coefficients, const ExactSolution& exact, int points_u, int points_v,
                      std::array<double, 2>& squares, Eigen::VectorXd* h1_per_element, CellRange cells = {}) const override;
  bool all_elements_affine() const override { return affine_elements() == long(u_.elements) * v_.elements; }
  // The matrix written in place, with no scatter: straight from the Kronecker form where the
  // map is one affine map and the functions are B-splines (solver/tensor_operator_matrix.cpp,
  // per entry four products of band entries); elsewhere (curved or piecewise-affine maps, NURBS
  // spaces) by sum factorization, a column of element rows at a time
  // (solver/tensor_operator_sum_factorized.cpp). Throws GeometryError, naming the lowest cell,
  // where det J <= 0 at a point. Rows alone (row_entries) only from the Kronecker form.
  bool assembles_lower() const override { return kronecker_writes() || net_->rows() > 0; }
  bool writes_rows() const override { return kronecker_writes(); }
  const char* assembly_method() const override { return kronecker_writes() ? "kronecker_form" : "sum_factorization"; }
  Eigen::SparseMatrix<double> lower_matrix(const DofLayout& layout) const override;
  void row_entries(int row, int count, const int* columns, double* values) const override;
  bool gives_pattern() const override { return true; }
  Eigen::SparseMatrix<double> lower_pattern(const DofLayout& layout) const override;
  void coupled_functions(int function, std::vector<int>& out) const override;
  // Whether every element also has the same factors (applied in Kronecker form), and they.
  bool uniform_factors() const { return uniform_; }
  const std::array<double, 4>& factors() const { return uniform_factors_; }
  // The operator of a patch whose elements all have `factors` ((H, -F, E) / |det J| and
  // |det J| in parameter coordinates, as factors() gives) on the spaces u x v, without a
  // geometry net (load() refuses): a multigrid's coarse level of a uniformly affine patch,
  // whose map is the same affine one on every mesh.
  static std::unique_ptr<TensorPoissonOperator> uniformly_affine(const BSplineBasis1D& space_u, const BSplineBasis1D& space_v,
                                                                 const std::array<double, 4>& factors, double stiffness,
                                                                 double reaction, int points_u, int points_v);
  // How many elements have an affine map (applied from univariate matrices, with no geometry).
  long affine_elements() const {
    if (uniform_) return long(u_.elements) * v_.elements;
    long n = 0;
    for (const auto& f : affine_) n += f[3] > 0;
    return n;
  }

  // A rectangle of functions: u indices first_u .. first_u + count_u - 1, v likewise, numbered
  // (i - first_u) + count_u (j - first_v).
  struct FunctionBox {
    int first_u = 0, count_u = 0, first_v = 0, count_v = 0;
  };
  // y = (K x) at the functions of `rows` (y numbered as `rows`), x given at the functions of
  // `given` and zero at the others: a block smoother's residual, from the elements that touch
  // the rows only ((m + p)^2 elements for m x m rows). Serial: callers run blocks in parallel.
  void apply_rows(const double* x, const FunctionBox& given, const FunctionBox& rows, double* y) const;
  // The same over all of `given` (y numbered as `given`), threaded over bands of rows.
  void apply_within(const double* x, const FunctionBox& given, double* y) const;

  // What the operator was made of, for a coarser operator of the same problem (the multigrid's
  // rediscretized levels, solver/tensor_multigrid.cpp): the bases, the weights (empty when
  // equal) and the geometry's homogeneous net (of weights 1 when they are equal: scaled to 1,
  // or 1 to 64 eps when read in place).
  const BSplineBasis1D& space_u() const { return space_u_; }
  const BSplineBasis1D& space_v() const { return space_v_; }
  const BSplineBasis1D& geometry_u() const { return geometry_u_; }
  const BSplineBasis1D& geometry_v() const { return geometry_v_; }
  const Eigen::VectorXd& weights() const { return weights_; }
  const Eigen::MatrixX3d& net() const { return *net_; }
  double stiffness() const { return stiffness_; }
  double reaction() const { return reaction_; }
  int points_u() const { return u_.points; }
  int points_v() const { return v_.points; }

 private:
  struct Direction {
    int degree = 0, geometry_degree = 0, points = 0, elements = 0;
    std::vector<int> first, geometry_first;  // per element: its first function, first net index
    // Per element, point-major: values then derivatives (d/dparameter) of the p + 1 functions
    // alive there, and of the geometry's g + 1; and the rule's weights times the length.
    std::vector<double> value, derivative, geometry_value, geometry_derivative, weight;
    // Per element, (p+1) x (p+1), row-major: sum_i w_i of N_a' N_c', N_a N_c and N_a' N_c (the
    // element's univariate stiffness, mass and mixed matrices, for affine elements).
    std::vector<double> stiffness, mass, mixed;
  };
  static Direction direction(const BSplineBasis1D& space, const BSplineBasis1D& geometry, int points);
  // p + 1 when every size (functions and points, both directions, geometry too) is p + 1, else 0.
  int uniform_size() const;
  void find_affine_elements();
  bool net_is_affine() const;
  // Every element, threaded: kernel(eu, ev, first u function, first v function, tables, Points)
  // with the geometry at its points; or, given `affine`, affine(eu, ev, fu, fv, factors) for the
  // elements that have constant factors, without the geometry.
  // `stop`: once it is true, the remaining elements are skipped.
  // `elements` (first and last element in u, then in v, inclusive): only those, serially.
  // `rule_u`, `rule_v`: other tables (another rule) than the operator's.
  // N > 0: every function and geometry size is N; Q > 0: every point count is Q (known to the
  // compiler: unrolled and vectorized contractions).
  template <int N, int Q = N, class Kernel, class Affine = std::nullptr_t>
  void for_each_element(Kernel kernel, Affine affine = nullptr, const std::atomic<bool>* stop = nullptr,
                        const std::array<int, 4>* elements = nullptr, const Direction* rule_u = nullptr,
                        const Direction* rule_v = nullptr) const;
  // The element's constant factors (H, -F, E) / |det J| and |det J|, when its map is affine
  // (they are the same at every point, to 64 eps); null otherwise.
  const std::array<double, 4>* affine_factors(int eu, int ev) const {
    if (affine_.empty()) return nullptr;
    const std::array<double, 4>& f = affine_[size_t(eu) + size_t(u_.elements) * ev];
    return f[3] > 0 ? &f : nullptr;
  }
  // y = K x element by element: gather(i, j) reads x at function (i, j) (times its weight when
  // rational), scatter(i, j, value) adds into y; over `elements` only when given.
  template <int N, class Gather, class Scatter>
  void product(Gather gather, Scatter scatter, const std::array<int, 4>* elements) const;
  template <class Sized>
  void dispatch(Sized sized) const;
  // sized(N, Q) for the tables U, V: N when every function and geometry size is N, Q when every
  // point count is Q (each 0 otherwise, or beyond the sizes compiled).
  template <class Sized>
  void dispatch(const Direction& U, const Direction& V, Sized sized) const;
  // The elements whose functions meet the box's rows (inclusive ranges); false when none do.
  bool elements_touching(const FunctionBox& rows, std::array<int, 4>& elements) const;

  // The univariate matrices assembled over the whole direction, as bands: entry (i, i + k - p)
  // at i (2p + 1) + k.
  struct Band {
    int n = 0;                    // functions
    std::vector<double> K, M, C;  // stiffness, mass, mixed (derivative on the row's function)
  };
  static Band band(const Direction& d);
  // The Kronecker form's coefficients along u, band entry k of row i at k n + i (k-major: the
  // pass runs along rows, vectorized), zero outside the matrix, the factors folded in:
  // a1 = d11 K_u + c M_u, a2 = d22 M_u, a3 = d12 C_u, a4 = d12 C_u^T. Along v the bands M_v,
  // K_v, C_v as they are, and C_v^T (cvt, row-major like them).
  struct KroneckerForm {
    std::vector<double> a1, a2, a3, a4, cvt;
    bool mixed = false;  // d12 != 0
  };
  // Sets uniform_ with `factors`, the bands and the Kronecker form.
  void set_uniform(const std::array<double, 4>& factors);
  // K's entry between functions (i, j) and (i0, j0) from the Kronecker form's bands, for
  // |i - i0| <= p_u and |j - j0| <= p_v (zero there where they share no element).
  struct KroneckerEntries {
    double d11 = 0, d12 = 0, d22 = 0, r = 0;
    int pu = 0, pv = 0;
    const double *ku = nullptr, *mu = nullptr, *cu = nullptr, *kv = nullptr, *mv = nullptr, *cv = nullptr;
    double operator()(int i, int j, int i0, int j0) const {
      // X(a, c) of a band sits at a (2p + 1) + c - a + p.
      const size_t wu = 2 * pu + 1, wv = 2 * pv + 1;
      const size_t u = i * wu + (i0 - i + pu), ut = i0 * wu + (i - i0 + pu);
      const size_t v = j * wv + (j0 - j + pv), vt = j0 * wv + (j - j0 + pv);
      double k = d11 * ku[u] * mv[v] + d22 * mu[u] * kv[v] + r * mu[u] * mv[v];
      if (d12 != 0) k += d12 * (cu[u] * cv[vt] + cu[ut] * cv[v]);
      return k;
    }
  };
  KroneckerEntries kronecker_entries() const;
  // Per function of one direction, the functions it shares an element with: [low, high].
  struct Reach {
    std::vector<int> low, high;
  };
  static Reach reach(const Direction& d, int functions);
  // K's lower triangle over the free dofs, with values (the Kronecker form) or zeros.
  Eigen::SparseMatrix<double> write_lower(const DofLayout& layout, bool values) const;
  bool kronecker_writes() const { return uniform_ && weights_.size() == 0; }
  // The coefficients of K at every point of element row ev, in the three kinds of product
  // functions' parameter terms (N_u' N_v, N_u N_v', N_u N_v): the symmetric 3 x 3 matrix
  // P^T (c_s D) P + c_r m / W^2 e3 e3^T, with P the rational functions' quotient rule (the
  // identity's first two rows for B-splines), stored as d[k][j * (E_u q_u) + (eu q_u + i)] for
  // k = 00, 01, 02, 11, 12, 22 (02 and 12 empty for B-splines). Also the row's smallest det J
  // and its first element there (-1: none <= 0).
  struct RowCoefficients {
    int element_row = -1;
    std::vector<double> d[6];
    double min_det = 0;
    int bad_element = -1;
  };
  void row_coefficients(int ev, RowCoefficients& out) const;
  // K's lower triangle by sum factorization over the free dofs (any map, B-splines or NURBS).
  Eigen::SparseMatrix<double> sum_factorized_lower(const DofLayout& layout) const;
  // y at `rows` from x on the padded box of rows +- the degrees (in, mu x mv) by the Kronecker
  // form of a patch whose elements share their factors.
  void kronecker_rows(const double* in, long mu, const FunctionBox& rows, double* y) const;

  Direction u_, v_;
  TensorPoissonOperator() = default;
  // Every element has the factors uniform_factors_ (a map affine on the whole patch): then
  // K = d11 K_u (x) M_v + d22 M_u (x) K_v + d12 (C_u (x) C_v^T + C_u^T (x) C_v) + c M_u (x) M_v
  // with the bands below, about a tenth of the element-by-element flops.
  bool uniform_ = false;
  std::array<double, 4> uniform_factors_{};
  Band band_u_, band_v_;
  Reach reach_u_, reach_v_;
  KroneckerForm kronecker_;
  BSplineBasis1D space_u_, space_v_, geometry_u_, geometry_v_;
  int n_u_ = 0, n_v_ = 0, net_u_ = 0;
  Eigen::VectorXd weights_;  // empty: B-splines (or NURBS of equal weights, the same functions)
  Eigen::MatrixX3d own_net_;
  const Eigen::MatrixX3d* net_ = &own_net_;  // own_net_, or the patch's (geometry_outlives_operator)
  bool polynomial_map_ = false;  // the net's weights are equal (then scaled to 1)
  // Per element (eu + n_eu ev), its affine factors, when every element is affine and they
  // differ; empty otherwise (the search stops at the first curved element), when uniform_ and
  // for NURBS spaces (whose functions are not products there).
  std::vector<std::array<double, 4>> affine_;
  double stiffness_ = 1, reaction_ = 0;
};

}  // namespace knotwork
