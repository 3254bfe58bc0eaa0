#include "solver/assemble_poisson.hpp"

#include <omp.h>

#include <Eigen/SparseCholesky>
#include "solver/linear_solver.hpp"
#include <algorithm>
#include <cmath>
#include <map>
#include <limits>
#include <sstream>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <array>
#include <optional>

#include "quadrature/bernstein.hpp"
#include "solver/cell_basis.hpp"
#include "solver/diffusion_at_points.hpp"
#include "basis/core/input_error.hpp"
#include "solver/separable_cells.hpp"
#include "solver/surface_source.hpp"

namespace knotwork {

std::string describe_cell(int c, double u0, double u1, double v0, double v1) {
  std::ostringstream s;
  s << "cell " << c << " (u in [" << u0 << ", " << u1 << "], v in [" << v0 << ", " << v1 << "])";
  return s.str();
}

namespace {

std::string describe_cell(const BezierMesh& mesh, int c) {
  const BezierCell& cell = mesh.cell(c);
  std::string text = knotwork::describe_cell(c, cell.u0, cell.u1, cell.v0, cell.v1);
  if (cell.dimension == 3) {  // a hexahedron: its w interval too
    std::ostringstream w;
    w << ", w in [" << cell.w0 << ", " << cell.w1 << "])";
    text.replace(text.size() - 1, 1, w.str());
  }
  return text;
}

// The first point (lowest cell) where A is not positive definite or c is negative.
struct CoefficientFailure {
  int cell = -1;
  double x = 0, y = 0, z = 0;
  bool surface = false;
  std::string field, what;
};

// Checks A (positive definite) and c (>= 0, finite) at the cell's points; records the first
// failure (lowest cell) and returns false on one.
// The unit normal at point q of a surface cell (jacobian columns x_u x_v y_u y_v z_u z_v).
Eigen::Vector3d unit_normal(const Eigen::MatrixXd& J, Eigen::Index q) {
  const Eigen::Vector3d xu(J(q, 0), J(q, 2), J(q, 4)), xv(J(q, 1), J(q, 3), J(q, 5));
  return xu.cross(xv).normalized();
}

// The symmetric matrix of the six entries a11 a12 a13 a22 a23 a33 at point q.
Eigen::Matrix3d matrix_at(const ExpressionBatch& values, Eigen::Index q) {
  Eigen::Matrix3d A;
  A << values.result(0)[q], values.result(1)[q], values.result(2)[q], values.result(1)[q], values.result(3)[q],
      values.result(4)[q], values.result(2)[q], values.result(4)[q], values.result(5)[q];
  return A;
}

// On a surface only the tangential part P A P of a 3x3 A acts. B = P A P + n n^T agrees with
// it on tangent vectors and is positive definite exactly when P A P is on the tangent plane:
// its Cholesky factor both checks A and gives the L^T applied to surface gradients.
Eigen::LLT<Eigen::Matrix3d> tangential_factor(const Eigen::Matrix3d& A, const Eigen::Vector3d& n) {
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - n * n.transpose();
  return Eigen::LLT<Eigen::Matrix3d>(P * A * P + n * n.transpose());
}

// With six entries `tangential` receives at every point L^T, with L L^T the factor of A on a
// volume and of tangential_factor on a surface, for apply_diffusion_factor: each is factored once.
bool coefficients_admissible(const PoissonCoefficients& k, const ExpressionBatch& values, const GeometryAtPoints& at,
                             bool volume, int cell, CoefficientFailure& failure, std::vector<Eigen::Matrix3d>& tangential) {
  const Eigen::MatrixXd& x = at.x;
  const Eigen::Index nq = x.rows();
  const int nd = static_cast<int>(k.diffusion.size());
  for (Eigen::Index q = 0; q < nq; ++q) {
    std::string what;
    const Expression* field = nullptr;
    bool matrix = false;
    if (nd == 1) {
      const double a = values.result(0)[q];
      if (!(a > 0) || !std::isfinite(a)) {
        std::ostringstream m;
        m << "the coefficient a = " << a << " is not positive";
        what = m.str();
        field = &k.diffusion[0];
      }
    } else if (nd == 3) {
      const double a11 = values.result(0)[q], a12 = values.result(1)[q], a22 = values.result(2)[q];
      if (!(a11 > 0 && a11 * a22 - a12 * a12 > 0) || !std::isfinite(a11 + a12 + a22)) {
        std::ostringstream m;
        m << "the coefficient matrix [[" << a11 << ", " << a12 << "], [" << a12 << ", " << a22
          << "]] is not positive definite";
        what = m.str();
        field = &k.diffusion[0];
        matrix = true;
      }
    } else if (nd == 6) {
      const Eigen::Matrix3d A = matrix_at(values, q);
      const Eigen::LLT<Eigen::Matrix3d> factor =
          volume ? Eigen::LLT<Eigen::Matrix3d>(A) : tangential_factor(A, unit_normal(at.jacobian, q));
      if (tangential.size() < static_cast<size_t>(nq)) tangential.resize(nq);
      tangential[q] = factor.matrixU();
      if (!A.allFinite() || factor.info() != Eigen::Success) {
        const Eigen::IOFormat row(Eigen::StreamPrecision, Eigen::DontAlignCols, ", ", ", ", "[", "]", "[", "]");
        std::ostringstream m;
        m << "the coefficient matrix " << A.format(row) << " is not positive definite" << (volume ? "" : " on the tangent plane");
        what = m.str();
        field = &k.diffusion[0];
        matrix = true;
      }
    }
    if (!field && !k.reaction.empty()) {
      const double c = values.result(nd)[q];
      if (!(c >= 0) || !std::isfinite(c)) {
        std::ostringstream m;
        m << "the reaction c = " << c << " is negative";
        what = m.str();
        field = &k.reaction;
      }
    }
    if (!field) continue;
#pragma omp critical(knotwork_bad_coefficient)
    if (failure.cell < 0 || cell < failure.cell) {
      failure.cell = cell;
      failure.x = x(q, 0);
      failure.y = x(q, 1);
      failure.surface = x.cols() == 3;
      if (failure.surface) failure.z = x(q, 2);
      failure.field = matrix && !k.diffusion_where.empty() ? k.diffusion_where : field->where();
      failure.what = what;
    }
    return false;
  }
  return true;
}

// Rows d * nq + q of G (the scaled gradients, per coordinate d and point q) become L^T g at
// each point, A = L L^T: a scalar a scales them by sqrt(a); a 2x2 matrix by its Cholesky factor.
void apply_diffusion_factor(const ExpressionBatch& values, int num_diffusion, int dim, Eigen::Index nq,
                            const std::vector<Eigen::Matrix3d>& tangential, Eigen::MatrixXd& G) {
  if (num_diffusion == 1) {
    const Eigen::Map<const Eigen::ArrayXd> a(values.result(0), nq);
    const Eigen::VectorXd root = a.sqrt().matrix();
    for (int d = 0; d < dim; ++d) G.middleRows(d * nq, nq) = root.asDiagonal() * G.middleRows(d * nq, nq);
    return;
  }
  if (num_diffusion == 6) {  // L^T of A (a volume) or of P A P + n n^T (a surface), from coefficients_admissible
    Eigen::Matrix3Xd rows(3, G.cols());
    for (Eigen::Index q = 0; q < nq; ++q) {
      for (int d = 0; d < 3; ++d) rows.row(d) = G.row(d * nq + q);
      rows = tangential[q] * rows;
      for (int d = 0; d < 3; ++d) G.row(d * nq + q) = rows.row(d);
    }
    return;
  }
  for (Eigen::Index q = 0; q < nq; ++q) {
    const double a11 = values.result(0)[q], a12 = values.result(1)[q], a22 = values.result(2)[q];
    const double l11 = std::sqrt(a11), l21 = a12 / l11, l22 = std::sqrt(a22 - l21 * l21);
    // L^T = [[l11, l21], [0, l22]]
    G.row(q) = l11 * G.row(q) + l21 * G.row(nq + q);
    G.row(nq + q) *= l22;
  }
}

// Adds the element matrix into the lower-triangular CSC values: for each alive free
// column, walk its sorted rows and the cell's sorted dofs together. The same walk fills the
// upper triangle of a rank's diagonal block by rows (CSR), outer[i] being row i's diagonal
// entry (scatter_rows).
void scatter(const int* outer, const int* inner, const std::vector<std::pair<int, int>>& order,
             const Eigen::MatrixXd& Ke, double* values) {
  const int m = static_cast<int>(order.size());
  for (int k = 0; k < m; ++k) {
    const int col = order[k].first, b = order[k].second;
    int ptr = outer[col];
    for (int l = k; l < m; ++l) {
      const int row = order[l].first;
      while (inner[ptr] < row) ++ptr;
      values[ptr] += Ke(order[l].second, b);
    }
  }
}

}  // namespace

namespace {

// The element loop shared by the serial matrix (CSC, lower triangle) and the distributed one:
// every cell of `cells`, threaded, integrated once; emit(thread, order, Ke, Fe) receives the
// cell's free dofs (sorted (dof, local index) pairs), its element matrix (all alive
// functions) and its load with the Dirichlet lifting applied. integrals_of(thread) gives the
// thread's vector of function integrals, or null.
template <class Emit, class Integrals>
void assemble_cells(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                    const DofLayout& layout, const Eigen::VectorXd& fixed_values, const QuadratureOptions& quadrature,
                    CellRange cells, Emit emit, Integrals integrals_of) {
  // dim: the physical space's, the gradients' components. A surface is dim 3 with quadrilateral
  // cells, a volume dim 3 with hexahedra (grad = J^{-T} grad_ref: nothing surface-specific).
  const int dim = geometry.dimension();
  const bool volume = geometry.parametric_dimension() == 3;
  const bool surface = dim == 3 && !volume;
  const bool derived = form.load && !form.source;
  if (derived && (!form.exact || form.exact->hessian[0][0].empty() || !surface))
    throw std::invalid_argument("assemble_poisson: no source, and no exact solution on a surface to derive it from");
  const int first = cells.first, last = cells.last < 0 ? mesh.num_cells() : cells.last;
  std::optional<ExpressionBatch> compiled_source;  // merged once; each thread runs its own copy
  if (form.load && form.source) compiled_source.emplace(std::vector<Expression>{*form.source});
  std::optional<SeparableMesh> separable;
  if (quadrature.separable_cells) separable.emplace(mesh);
  // Variable A and c: compiled once (entries of A first, then c), evaluated per cell.
  const PoissonCoefficients* variable = form.coefficients && !form.coefficients->constant() ? form.coefficients : nullptr;
  const int num_diffusion = variable ? static_cast<int>(variable->diffusion.size()) : 0;
  const bool variable_reaction = variable && !variable->reaction.empty();
  std::optional<ExpressionBatch> compiled_coefficients;
  if (variable) {
    // A matrix is 2x2 (three entries) in the plane and 3x3 (six) on a surface or a volume: the readers see to it.
    if ((num_diffusion == 3 && dim != 2) || (num_diffusion == 6 && dim != 3))
      throw std::logic_error("assemble_poisson: a coefficient matrix of the wrong size for the domain");
    std::vector<Expression> all = variable->diffusion;
    if (variable_reaction) all.push_back(variable->reaction);
    compiled_coefficients.emplace(all);
  }
  CoefficientFailure bad_coefficient;
  // The derived surface source needs the ambient derivatives of A's entries: differentiated
  // once here (GiNaC is not thread-safe).
  std::vector<ExactSolution> surface_coefficient;
  if (derived && form.source_coefficients)
    for (const Expression& a : form.source_coefficients->diffusion) surface_coefficient.push_back(differentiate_surface_solution(a));
  const Expression* surface_reaction =
      form.source_coefficients && !form.source_coefficients->reaction.empty() ? &form.source_coefficients->reaction : nullptr;
  // Nitsche's boundary terms first, serially (few cells; the data's evaluators are not
  // shared between threads), then added to their cells' element matrices in the loop.
  std::vector<NitscheCellTerms> nitsche;
  std::vector<int> nitsche_of_cell;
  if (form.nitsche) {
    nitsche = nitsche_terms(mesh, geometry, *form.nitsche, quadrature, CellRange{first, last});
    nitsche_of_cell.assign(last - first, -1);
    for (size_t k = 0; k < nitsche.size(); ++k) nitsche_of_cell[nitsche[k].cell - first] = static_cast<int>(k);
  }
  int bad_cell = std::numeric_limits<int>::max(), bad_source_cell = bad_cell;
  double bad_det = 0, bad_x = 0, bad_y = 0, bad_z = 0;
  std::string failure;

#pragma omp parallel
  {
    const int tid = omp_get_thread_num();
    Eigen::VectorXd* my_integrals = integrals_of(tid);
    std::optional<ExpressionBatch> f;
    if (compiled_source) f.emplace(*compiled_source);
    std::optional<ExpressionBatch> coefficient_values;
    if (compiled_coefficients) coefficient_values.emplace(*compiled_coefficients);
    Eigen::ArrayXd reaction_root;
    std::vector<Eigen::Matrix3d> tangential;  // per point, a surface's 3x3 coefficient factored
    std::optional<DerivedSurfaceSource> derived_f;
    if (derived) derived_f.emplace(*form.exact, surface_coefficient, surface_reaction, form.source_reaction);
    CellBasis cb;
    CellFunctions cf;
    Eigen::MatrixXd G, KB, Ke, second;
    Eigen::VectorXd fq, FB, Fe, ulift;
    Eigen::ArrayXd root;
    std::vector<std::pair<int, int>> order;
    // A fixed assignment of cells to threads (and the thread sums added in thread order
    // below): the matrix and load are bitwise the same from run to run.
#pragma omp for schedule(static, 64)
    for (int c = first; c < last; ++c) {
      const BezierCell& cell = mesh.cell(c);
      const int nu = rule_points(quadrature.points_u, cell.degree_u, 1);
      const int nv = rule_points(quadrature.points_v, cell.degree_v, 1);
      const SeparableExtraction* rows = separable ? separable->of_cell(mesh, c) : nullptr;
      if (rows) evaluate_cell_functions(mesh, geometry, *rows, c, nu, nv, cf);
      else if (volume) evaluate_volume_cell_basis(mesh, geometry, c, nu, nv, rule_points(quadrature.points_w, cell.degree_w, 1), cb);
      else evaluate_cell_basis(mesh, geometry, c, nu, nv, cb);
      const double min_jacobian = rows ? cf.min_jacobian : cb.min_jacobian;
      const Eigen::VectorXd& measure = rows ? cf.measure : cb.measure;
      const GeometryAtPoints& at = rows ? cf.geometry : cb.geometry;
      if (!(min_jacobian > 0)) {
#pragma omp critical(knotwork_bad_cell)
        if (c < bad_cell) { bad_cell = c; bad_det = min_jacobian; }
        continue;
      }
      const Eigen::Index nq = measure.size();
      fq.resize(nq);
      if (f) {
        f->evaluate(at.x.col(0).data(), at.x.col(1).data(), dim == 3 ? at.x.col(2).data() : nullptr, nq);
        fq = Eigen::Map<const Eigen::VectorXd>(f->result(0), nq);
      } else if (derived_f) {
        const BernsteinTable& t = bernstein_table(1, 1, nu, nv);
        if (!geometry.second_derivatives(c, t.point_u, t.point_v, second)) {
#pragma omp critical(knotwork_bad_cell)
          failure = "the geometry has no second derivatives, needed for the curvature of the derived source";
          continue;
        }
        (*derived_f)(at.x, at.jacobian, second, fq);
      } else {
        fq.setZero();
      }
      for (Eigen::Index k = 0; k < nq; ++k)
        if (!std::isfinite(fq[k])) {
#pragma omp critical(knotwork_bad_cell)
          if (c < bad_source_cell) {
            bad_source_cell = c;
            bad_x = at.x(k, 0), bad_y = at.x(k, 1), bad_z = dim == 3 ? at.x(k, 2) : 0;
          }
          fq[k] = 0;
        }
      // sum_q m_q (grad phi grad phi^T): one dense product on stacked, scaled gradients, of
      // the cell's functions (separable cells) or of its Bernstein polynomials, then C K C^T.
      if (!rows || form.reaction != 0) root = measure.array().sqrt();
      const Eigen::MatrixXd& value = rows ? cf.value : cb.value;
      Eigen::MatrixXd& K = rows ? Ke : KB;
      if (coefficient_values) {
        coefficient_values->evaluate(at.x.col(0).data(), at.x.col(1).data(), dim == 3 ? at.x.col(2).data() : nullptr, nq);
        if (!coefficients_admissible(*variable, *coefficient_values, at, volume, c, bad_coefficient, tangential)) continue;
        if (variable_reaction)
          reaction_root = (measure.array() * Eigen::Map<const Eigen::ArrayXd>(coefficient_values->result(num_diffusion), nq)).sqrt();
      }
      if (form.stiffness != 0) {
        if (!rows) {
          G.resize(dim * nq, value.cols());
          for (int d = 0; d < dim; ++d) G.middleRows(d * nq, nq) = root.matrix().asDiagonal() * cb.grad(d);
        } else if (num_diffusion > 0) {
          G = cf.scaled_gradients;
        }
        // A = L L^T at each point: the stacked gradients become L^T grad phi, so that the same
        // product gives sum_q m_q grad phi^T A grad phi.
        if (num_diffusion > 0) apply_diffusion_factor(*coefficient_values, num_diffusion, dim, nq, tangential, G);
        // The lower triangle by a symmetric rank update (half the flops of G^T G), mirrored.
        K.setZero(value.cols(), value.cols());
        K.selfadjointView<Eigen::Lower>().rankUpdate((rows && num_diffusion == 0 ? cf.scaled_gradients : G).transpose(),
                                                     form.stiffness);
        K.triangularView<Eigen::StrictlyUpper>() = K.transpose();
      } else {
        K.setZero(value.cols(), value.cols());
      }
      if (form.reaction != 0) {
        G.noalias() = (variable_reaction ? reaction_root : root).matrix().asDiagonal() * value;
        K.noalias() += form.reaction * (G.transpose() * G);
      }
      fq.array() *= measure.array();  // the load's weights m_q f(x_q), in place
      if (rows) {
        Fe.noalias() = value.transpose() * fq;
      } else {
        FB.noalias() = value.transpose() * fq;
        Ke.noalias() = cb.C * KB * cb.C.transpose();
        Fe.noalias() = cb.C * FB;
      }
      if (form.nitsche && nitsche_of_cell[c - first] >= 0) {
        const NitscheCellTerms& boundary = nitsche[nitsche_of_cell[c - first]];
        Ke += boundary.matrix;
        if (form.load) Fe += boundary.load;
      }
      const auto ids = mesh.functions(c);
      if (my_integrals) {
        const Eigen::VectorXd Ie = rows ? Eigen::VectorXd(cf.value.transpose() * measure)
                                        : Eigen::VectorXd(cb.C * (cb.value.transpose() * measure));
        for (size_t a = 0; a < ids.size(); ++a) (*my_integrals)[ids[a]] += Ie[a];
      }
      order.clear();
      bool lifted = false;
      ulift.setZero(ids.size());
      for (size_t a = 0; a < ids.size(); ++a) {
        const int d = layout.dof[ids[a]];
        if (d >= 0) order.emplace_back(d, static_cast<int>(a));
        else { ulift[a] = fixed_values[ids[a]]; lifted = lifted || ulift[a] != 0.0; }
      }
      if (lifted) Fe.noalias() -= Ke * ulift;
      std::sort(order.begin(), order.end());
      emit(tid, order, Ke, Fe);
    }
  }
  if (!failure.empty()) throw std::invalid_argument(failure);
  if (bad_coefficient.cell >= 0 && bad_coefficient.cell < bad_cell) {
    std::ostringstream m;
    m << ": " << bad_coefficient.what << " at (" << bad_coefficient.x << ", " << bad_coefficient.y;
    if (bad_coefficient.surface) m << ", " << bad_coefficient.z;
    m << ") in "
      << describe_cell(mesh, bad_coefficient.cell);
    throw InputError(bad_coefficient.field + m.str());
  }
  if (bad_cell != std::numeric_limits<int>::max()) {
    std::ostringstream s;
    if (dim == 2 || volume)
      s << "geometry has a non-positive Jacobian (det J = " << bad_det << ") at a quadrature point of "
        << describe_cell(mesh, bad_cell)
        << (bad_det == 0 ? ": the map is degenerate there (a collapsed edge or corner, or a domain too small for "
                           "double precision)"
                         : volume ? ": the map folds over or is left-handed (u, v, w must be a right-handed frame)"
                                  : ": the map folds over or is oriented clockwise");
    else
      s << "the surface degenerates (area element " << bad_det << ") at a quadrature point of "
        << describe_cell(mesh, bad_cell);
    throw GeometryError(s.str());
  }
  if (bad_source_cell != std::numeric_limits<int>::max()) {
    std::ostringstream s;
    const Expression& e = form.source ? *form.source : form.exact->u;
    s << (form.source ? "source \"" : "the source derived from \"") << e.text() << "\" is not a finite number at (";
    s << bad_x << ", " << bad_y;
    if (dim == 3) s << ", " << bad_z;
    s << ") in " << describe_cell(mesh, bad_source_cell);
    throw InputError(e.where() + ": " + s.str());
  }
}

}  // namespace

PoissonForm poisson_form(const PoissonProblem& problem) {
  PoissonForm form;
  const bool variable_reaction = !problem.coefficients.reaction.empty();
  form.reaction = variable_reaction ? 1.0 : problem.reaction;
  form.source_reaction = problem.reaction;
  form.coefficients = problem.coefficients.constant() ? nullptr : &problem.coefficients;
  if (!problem.coefficients.constant()) form.source_coefficients = &problem.coefficients;
  form.source = problem.source.empty() ? nullptr : &problem.source;
  form.exact = problem.exact ? &*problem.exact : nullptr;
  if (problem.dirichlet_method == DirichletMethod::kNitsche) form.nitsche = &problem;
  return form;
}

PoissonForm mass_form(const PoissonForm& form) {
  PoissonForm mass = form;
  mass.stiffness = 0;
  mass.reaction = 1;
  mass.load = false;
  mass.nitsche = nullptr;
  mass.coefficients = nullptr;
  return mass;
}

bool without_reaction(const PoissonProblem& problem) {
  return problem.reaction == 0 && problem.coefficients.reaction.empty();
}

namespace {

// assemble_cells into one array of matrix values (nnz entries; scatter(order, Ke, values) adds
// a cell's entries) and the load. Thread 0 adds into the results, the others into their own
// copies (allocated by their thread, before its first cell), summed in thread order after the
// loop: the sums do not depend on timing.
template <class Scatter>
void assemble_values(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                     const DofLayout& layout, const Eigen::VectorXd& fixed_values, const QuadratureOptions& quadrature,
                     double* values, long nnz, Scatter scatter, Eigen::VectorXd& rhs, Eigen::VectorXd* integrals,
                     CellRange cells) {
  const int nthreads = omp_get_max_threads();
  std::fill(values, values + nnz, 0.0);
  rhs.setZero(layout.num_free());
  if (integrals) integrals->setZero(mesh.num_functions());
  std::vector<std::vector<double>> thread_values(nthreads - 1, std::vector<double>());
  std::vector<Eigen::VectorXd> thread_rhs(nthreads - 1), thread_integrals(nthreads - 1);
  auto integrals_of = [&](int tid) -> Eigen::VectorXd* {
    if (tid == 0 || !integrals) return integrals;
    thread_integrals[tid - 1].setZero(mesh.num_functions());
    return &thread_integrals[tid - 1];
  };
  auto emit = [&](int tid, const std::vector<std::pair<int, int>>& order, const Eigen::MatrixXd& Ke,
                  const Eigen::VectorXd& Fe) {
    double* my_values = values;
    Eigen::VectorXd* my_rhs = &rhs;
    if (tid > 0) {
      if (thread_values[tid - 1].empty()) {
        thread_values[tid - 1].assign(nnz, 0.0);
        thread_rhs[tid - 1].setZero(layout.num_free());
      }
      my_values = thread_values[tid - 1].data();
      my_rhs = &thread_rhs[tid - 1];
    }
    for (const auto& [d, a] : order) (*my_rhs)[d] += Fe[a];
    scatter(order, Ke, my_values);
  };
  assemble_cells(mesh, geometry, form, layout, fixed_values, quadrature, cells, emit, integrals_of);
  for (int t = 0; t < nthreads - 1; ++t) {
    if (!thread_values[t].empty()) {
      const double* src = thread_values[t].data();
      double* dst = values;
#pragma omp parallel for schedule(static)
      for (long i = 0; i < nnz; ++i) dst[i] += src[i];
      rhs += thread_rhs[t];
    }
    if (integrals && thread_integrals[t].size() > 0) *integrals += thread_integrals[t];
  }
}

// A cell's rows into a rank's rows: an owned row's columns into the diagonal block (owned
// columns) or the off-diagonal one (by global row), a halo row's into its entries. In the
// diagonal block only the upper triangle (column >= row) is added here, walked from the row's
// diagonal entry (`diagonal`, its position) as the serial scatter walks a lower column from
// its diagonal: the lower triangle is its mirror image, copied once after the loop
// (mirror_diagonal_block), which costs less than adding 625 entries per cell instead of 325 at
// p = 4. Each row's sorted columns are walked once, as the cell's dofs ascend. Entry (i, j) is
// read from Ke's lower triangle in the cell's dof order, as the serial scatter reads it.
void scatter_rows(const RankRows& r, const std::vector<int>& diagonal, const std::vector<std::pair<int, int>>& order,
                  const Eigen::MatrixXd& Ke, double* values) {
  const OwnedRows& o = r.owned;
  const int m = static_cast<int>(order.size());
  if (m == 0) return;
  const auto own = [&](int d) { return d >= r.first && d < r.last; };
  const int* cols = o.diagonal_cols.data();
  if (own(order.front().first) && own(order.back().first)) {  // the usual cell: only the diagonal block
    // The serial kernel itself, on the block's rows from their diagonal entries, in the block's
    // numbering: written out here, inside the element loop's many live values, the walk kept
    // its cursor in memory and took 1.3x the serial walk's instructions (cachegrind).
    thread_local std::vector<std::pair<int, int>> local;
    local.resize(m);
    for (int k = 0; k < m; ++k) local[k] = {order[k].first - r.first, order[k].second};
    scatter(diagonal.data(), cols, local, Ke, values);
    return;
  }
  // Owned rows get owned columns (from the diagonal on) in the diagonal block, the others
  // (global rows) in the off-diagonal one: two walks, each along its block's sorted columns.
  double* off_values = values + o.diagonal_nonzeros();
  double* halo_values = values + r.halo_offset();
  for (int k = 0; k < m; ++k) {
    const auto [row, a] = order[k];
    const bool owned_row = own(row);
    int p = owned_row ? diagonal[row - r.first] : 0, off = owned_row ? o.off_start[row - r.first] : 0;
    int halo = owned_row ? 0 : r.halo_start[row];
    for (int l = 0; l < m; ++l) {
      const double v = l < k ? Ke(a, order[l].second) : Ke(order[l].second, a);
      const int col = order[l].first;
      if (!owned_row) {
        while (r.halo_cols[halo] < col) ++halo;
        halo_values[halo] += v;
      } else if (own(col)) {
        if (l < k) continue;  // the lower triangle: mirrored after the loop
        while (cols[p] < col - r.first) ++p;
        values[p] += v;
      } else {
        const int global = r.global_row[col];
        while (o.off_cols[off] < global) ++off;
        off_values[off] += v;
      }
    }
  }
}

}  // namespace

void assemble_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                      const DofLayout& layout, const Eigen::VectorXd& fixed_values,
                      const QuadratureOptions& quadrature, Eigen::SparseMatrix<double>& matrix,
                      Eigen::VectorXd& rhs, Eigen::VectorXd* integrals, CellRange cells) {
  const int* outer = matrix.outerIndexPtr();
  const int* inner = matrix.innerIndexPtr();
  assemble_values(
      mesh, geometry, form, layout, fixed_values, quadrature, matrix.valuePtr(), matrix.nonZeros(),
      [&](const std::vector<std::pair<int, int>>& order, const Eigen::MatrixXd& Ke, double* values) {
        scatter(outer, inner, order, Ke, values);
      },
      rhs, integrals, cells);
}

void assemble_poisson(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonForm& form,
                      const DofLayout& layout, const Eigen::VectorXd& fixed_values,
                      const QuadratureOptions& quadrature, RankRows& rows, Eigen::VectorXd& rhs, CellRange cells) {
  const std::vector<int> diagonal = diagonal_positions(rows.owned);
  assemble_values(
      mesh, geometry, form, layout, fixed_values, quadrature, rows.owned.values.data(),
      static_cast<long>(rows.owned.values.size()),
      [&](const std::vector<std::pair<int, int>>& order, const Eigen::MatrixXd& Ke, double* values) {
        scatter_rows(rows, diagonal, order, Ke, values);
      },
      rhs, nullptr, cells);
  mirror_diagonal_block(rows.owned, diagonal);
}

namespace {

// The evaluators of one condition's data: g or h (value), or grad u (from the exact
// solution) or a given flux vector F (gradient: x, y, and z on a volume's faces).
struct BoundaryEvaluators {
  std::optional<ExpressionEvaluator> value;
  std::vector<ExpressionEvaluator> gradient;
};

// Data g (Dirichlet) or h (Neumann) at the side's points.
// The Neumann data from the exact solution are the flux (A grad u).n, a given flux vector's F.n.
void boundary_data(const PoissonProblem& problem, const BoundaryCondition& bc, const CellBasis& cb,
                   BoundaryEvaluators& data, DiffusionAtPoints& diffusion, Eigen::VectorXd& out) {
  const Eigen::Index n = cb.measure.size();
  out.resize(n);
  const bool face = cb.geometry.parametric_dimension() == 3;
  const bool flux = bc.kind == BoundaryKind::kNeumann && (bc.from_exact || !bc.flux.empty());
  for (Eigen::Index k = 0; k < n; ++k) {
    const double x = cb.geometry.x(k, 0), y = cb.geometry.x(k, 1), z = face ? cb.geometry.x(k, 2) : 0.0;
    if (flux && face) {
      Eigen::Vector3d g(data.gradient[0](x, y, z), data.gradient[1](x, y, z), data.gradient[2](x, y, z));
      if (bc.from_exact && !diffusion.identity()) g = diffusion(x, y, z) * g;
      out[k] = g.dot(cb.normal.row(k).transpose());
    } else if (flux) {
      Eigen::Vector2d g(data.gradient[0](x, y), data.gradient[1](x, y));  // grad u, or the given flux vector
      if (bc.from_exact && !diffusion.identity()) g = diffusion(x, y) * g;
      out[k] = g[0] * cb.normal(k, 0) + g[1] * cb.normal(k, 1);
    } else {
      out[k] = face ? (*data.value)(x, y, z) : (*data.value)(x, y);
    }
    if (!std::isfinite(out[k])) {
      std::ostringstream s;
      const Expression& e = bc.from_exact ? problem.exact->u : bc.flux.empty() ? bc.value : bc.flux[0];
      s << e.where() << ": boundary data \"" << e.text() << "\" is not finite at (" << x << ", " << y;
      if (face) s << ", " << z;
      s << ")";
      throw InputError(s.str());
    }
  }
}

BoundaryEvaluators make_evaluators(const PoissonProblem& problem, const BoundaryCondition& bc, int dimension) {
  BoundaryEvaluators e;
  if (bc.from_exact) {
    if (!problem.exact) throw InputError("boundary data come from the exact solution, but none is given");
    e.value.emplace(problem.exact->u);
    if (bc.kind == BoundaryKind::kNeumann) {
      if (dimension == 3 && problem.exact->u_z.empty())
        throw std::logic_error("Neumann data on a volume's face: the exact solution has no u_z");
      for (const Expression* d : {&problem.exact->u_x, &problem.exact->u_y, &problem.exact->u_z})
        if (static_cast<int>(e.gradient.size()) < dimension) e.gradient.emplace_back(*d);
    }
  } else if (!bc.flux.empty()) {
    if (static_cast<int>(bc.flux.size()) != dimension)
      throw InputError(bc.flux[0].where() + ": a flux vector has " + std::to_string(dimension) +
                       " components here, got " + std::to_string(bc.flux.size()));
    for (const Expression& f : bc.flux) e.gradient.emplace_back(f);
  } else {
    e.value.emplace(bc.value);
  }
  return e;
}

int side_points(const QuadratureOptions& q, const BezierCell& cell) {
  if (q.boundary_points > 0) return q.boundary_points;
  int interior = std::max(rule_points(q.points_u, cell.degree_u, 1), rule_points(q.points_v, cell.degree_v, 1));
  if (cell.dimension == 3) interior = std::max(interior, rule_points(q.points_w, cell.degree_w, 1));
  return q.boundary_points < 0 ? interior : interior + 1;
}

// Calls visit(cell, side basis, boundary data at the side's points) for every cell side
// of `cells` that carries a condition of the given kind.
template <class Visit>
void for_each_boundary_side(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonProblem& problem,
                            const QuadratureOptions& quadrature, CellRange cells, BoundaryKind kind, Visit visit) {
  const int last = cells.last < 0 ? mesh.num_cells() : cells.last;
  CellBasis cb;
  Eigen::VectorXd data;
  for (size_t id = 0; id < problem.boundary.size(); ++id) {
    const BoundaryCondition& bc = problem.boundary[id];
    if (bc.kind != kind) continue;
    BoundaryEvaluators evaluators = make_evaluators(problem, bc, geometry.parametric_dimension() == 3 ? 3 : 2);
    DiffusionAtPoints diffusion(bc.kind == BoundaryKind::kNeumann && bc.from_exact ? problem.coefficients.diffusion
                                                                                   : std::vector<Expression>{});
    for (int c = cells.first; c < last; ++c)
      for (int s = 0; s < mesh.cell(c).num_sides(); ++s) {
        if (mesh.cell(c).boundary[s] != static_cast<int>(id)) continue;
        evaluate_side_basis(mesh, geometry, c, static_cast<CellSide>(s), side_points(quadrature, mesh.cell(c)), cb);
        boundary_data(problem, bc, cb, evaluators, diffusion, data);
        visit(c, cb, data);
      }
  }
}

}  // namespace

void add_neumann_terms(const BezierMesh& mesh, const GeometryMap& geometry,
                       const PoissonProblem& problem, const DofLayout& layout,
                       const QuadratureOptions& quadrature, Eigen::VectorXd& rhs, CellRange cells) {
  Eigen::VectorXd Fe;
  for_each_boundary_side(mesh, geometry, problem, quadrature, cells, BoundaryKind::kNeumann,
                         [&](int c, const CellBasis& cb, const Eigen::VectorXd& h) {
                           Fe.noalias() = cb.C * (cb.value.transpose() * cb.measure.cwiseProduct(h));
                           const auto ids = mesh.functions(c);
                           for (size_t a = 0; a < ids.size(); ++a)
                             if (layout.dof[ids[a]] >= 0) rhs[layout.dof[ids[a]]] += Fe[a];
                         });
}

std::vector<NitscheCellTerms> nitsche_terms(const BezierMesh& mesh, const GeometryMap& geometry,
                                            const PoissonProblem& problem, const QuadratureOptions& quadrature,
                                            CellRange cells) {
  // Per cell, in its Bernstein basis: A = sum over its Dirichlet sides of (dB/dn, dB/dn), the
  // symmetric part S = -(dB/dn, B) - (B, dB/dn), P = (B, B), and the loads -(g, dB/dn), (g, B).
  struct Pieces {
    Eigen::MatrixXd C, A, S, P;
    Eigen::VectorXd load_normal, load_value;
  };
  std::map<int, Pieces> of_cell;
  Eigen::MatrixXd dn;
  const bool volume = geometry.parametric_dimension() == 3;
  const int dims = volume ? 3 : 2;  // the normal's components (a plane's sides, a volume's faces)
  // With a coefficient A, dB/dn is the conormal derivative (A grad B).n and the penalty's bound
  // is taken against the A-weighted stiffness (the same coercivity argument in A's energy).
  DiffusionAtPoints diffusion(problem.coefficients.diffusion);
  Eigen::MatrixXd conormal_at;  // points x dims: A n
  const auto conormal = [&](const CellBasis& cb) {
    conormal_at = cb.normal.leftCols(dims);
    for (Eigen::Index k = 0; k < conormal_at.rows() && !diffusion.identity(); ++k) {
      const double x = cb.geometry.x(k, 0), y = cb.geometry.x(k, 1);
      if (volume) conormal_at.row(k) = (diffusion(x, y, cb.geometry.x(k, 2)) * conormal_at.row(k).transpose()).transpose();
      else conormal_at.row(k) = (diffusion(x, y) * conormal_at.row(k).transpose()).transpose();
    }
  };
  for_each_boundary_side(mesh, geometry, problem, quadrature, cells, BoundaryKind::kDirichlet,
                         [&](int c, const CellBasis& cb, const Eigen::VectorXd& g) {
                           Pieces& p = of_cell[c];
                           const Eigen::Index nb = cb.value.cols();
                           if (p.C.size() == 0) {
                             p.C = cb.C;
                             p.A.setZero(nb, nb), p.S.setZero(nb, nb), p.P.setZero(nb, nb);
                             p.load_normal.setZero(nb), p.load_value.setZero(nb);
                           }
                           conormal(cb);
                           dn = conormal_at.col(0).asDiagonal() * cb.grad_x;
                           for (int d = 1; d < dims; ++d) dn += conormal_at.col(d).asDiagonal() * cb.grad(d);
                           const Eigen::MatrixXd mdn = cb.measure.asDiagonal() * dn;
                           const Eigen::MatrixXd mixed = cb.value.transpose() * mdn;  // (B_i, dB_j/dn)
                           p.A.noalias() += dn.transpose() * mdn;
                           p.S -= mixed + mixed.transpose();
                           p.P.noalias() += cb.value.transpose() * cb.measure.asDiagonal() * cb.value;
                           p.load_normal.noalias() -= mdn.transpose() * g;
                           p.load_value.noalias() += cb.value.transpose() * cb.measure.cwiseProduct(g);
                         });
  std::vector<NitscheCellTerms> out;
  out.reserve(of_cell.size());
  CellBasis vb;
  for (auto& [c, p] : of_cell) {
    // lambda = max over the cell's polynomials v of |dv/dn|^2_D / |grad v|^2_K. Both forms vanish
    // on the constants (the Bernstein polynomials sum to 1), so the quotient is taken on the span
    // of all but the last Bernstein polynomial, where the stiffness is definite.
    const BezierCell& cell = mesh.cell(c);
    const int nu = rule_points(quadrature.points_u, cell.degree_u, 1), nv = rule_points(quadrature.points_v, cell.degree_v, 1);
    if (volume) evaluate_volume_cell_basis(mesh, geometry, c, nu, nv, rule_points(quadrature.points_w, cell.degree_w, 1), vb);
    else evaluate_cell_basis(mesh, geometry, c, nu, nv, vb);
    // A folded or degenerate cell is left to the element loop, which names it as for any cell.
    if (!(vb.min_jacobian > 0)) continue;
    const Eigen::Index m = vb.value.cols() - 1;
    Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(m + 1, m + 1);
    if (diffusion.identity()) {
      for (int d = 0; d < geometry.dimension(); ++d)
        stiffness.noalias() += vb.grad(d).transpose() * vb.measure.asDiagonal() * vb.grad(d);
    } else if (volume) {
      // sum_q m_q (A grad B)^T grad B with A = L L^T: the gradients stacked per point, times L^T.
      const Eigen::Index nq = vb.measure.size();
      Eigen::MatrixXd G(3 * nq, vb.value.cols());
      for (Eigen::Index k = 0; k < nq; ++k) {
        const Eigen::Matrix3d a = diffusion(vb.geometry.x(k, 0), vb.geometry.x(k, 1), vb.geometry.x(k, 2));
        const Eigen::Matrix3d lt = Eigen::LLT<Eigen::Matrix3d>(a).matrixL().transpose();
        Eigen::Matrix<double, 3, Eigen::Dynamic> g(3, vb.value.cols());
        for (int d = 0; d < 3; ++d) g.row(d) = vb.grad(d).row(k);
        G.middleRows(3 * k, 3) = std::sqrt(vb.measure[k]) * (lt * g);
      }
      stiffness.noalias() += G.transpose() * G;
    } else {
      const Eigen::Index nq = vb.measure.size();
      Eigen::VectorXd w11(nq), w12(nq), w22(nq);
      for (Eigen::Index k = 0; k < nq; ++k) {
        const Eigen::Matrix2d a = diffusion(vb.geometry.x(k, 0), vb.geometry.x(k, 1));
        w11[k] = vb.measure[k] * a(0, 0), w12[k] = vb.measure[k] * a(0, 1), w22[k] = vb.measure[k] * a(1, 1);
      }
      const Eigen::MatrixXd mixed = vb.grad_x.transpose() * w12.asDiagonal() * vb.grad_y;
      stiffness.noalias() += vb.grad_x.transpose() * w11.asDiagonal() * vb.grad_x +
                             vb.grad_y.transpose() * w22.asDiagonal() * vb.grad_y + mixed + mixed.transpose();
    }
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(p.A.topLeftCorner(m, m),
                                                                 stiffness.topLeftCorner(m, m), Eigen::EigenvaluesOnly);
    if (eig.info() != Eigen::Success || !std::isfinite(eig.eigenvalues().maxCoeff()))
      throw GeometryError("Nitsche's penalty: no bound on the normal derivative of " + describe_cell(mesh, c) +
                          " (its stiffness matrix is numerically singular: a nearly degenerate cell)");
    const double penalty = problem.nitsche_penalty * 2 * eig.eigenvalues().maxCoeff();
    NitscheCellTerms t;
    t.cell = c;
    t.matrix = p.C * (p.S + penalty * p.P) * p.C.transpose();
    t.load = p.C * (p.load_normal + penalty * p.load_value);
    out.push_back(std::move(t));
  }
  return out;
}

DirichletPieces dirichlet_pieces(const BezierMesh& mesh, const GeometryMap& geometry, const PoissonProblem& problem,
                                 const QuadratureOptions& quadrature, CellRange cells, const MeshPart& part) {
  DirichletPieces out;
  const int last = cells.last < 0 ? mesh.num_cells() : cells.last;
  auto is_dirichlet = [&](int id) {
    return problem.dirichlet_method == DirichletMethod::kProjection && id >= 0 &&
           problem.boundary.at(id).kind == BoundaryKind::kDirichlet;
  };
  // Functions whose trace on a Dirichlet side is not identically zero.
  std::vector<int> local(mesh.num_functions(), -1);
  for (int c = cells.first; c < last; ++c) {
    const BezierCell& cell = mesh.cell(c);
    for (int s = 0; s < cell.num_sides(); ++s) {
      if (!is_dirichlet(cell.boundary[s])) continue;
      const Eigen::MatrixXd& C = mesh.extraction(c);
      const auto ids = mesh.functions(c);
      const double scale = C.cwiseAbs().maxCoeff();
      const CellSide side = static_cast<CellSide>(s);
      for (int b : cell.dimension == 3 ? side_bernstein_indices(cell.degree_u, cell.degree_v, cell.degree_w, side)
                                       : side_bernstein_indices(cell.degree_u, cell.degree_v, side))
        for (Eigen::Index a = 0; a < C.rows(); ++a)
          if (std::abs(C(a, b)) > 1e-12 * scale && local[ids[a]] < 0) {
            local[ids[a]] = static_cast<int>(out.functions.size());
            out.functions.push_back(part.global(ids[a]));
          }
    }
  }
  out.load.assign(out.functions.size(), 0.0);
  for_each_boundary_side(mesh, geometry, problem, quadrature, cells, BoundaryKind::kDirichlet,
                         [&](int c, const CellBasis& cb, const Eigen::VectorXd& g) {
                           const Eigen::MatrixXd phi = cb.value * cb.C.transpose();  // points x alive
                           const Eigen::MatrixXd Me = phi.transpose() * cb.measure.asDiagonal() * phi;
                           const Eigen::VectorXd re = phi.transpose() * cb.measure.cwiseProduct(g);
                           const auto ids = mesh.functions(c);
                           for (size_t a = 0; a < ids.size(); ++a) {
                             if (local[ids[a]] < 0) continue;
                             out.load[local[ids[a]]] += re[a];
                             for (size_t b = 0; b < ids.size(); ++b)
                               if (local[ids[b]] >= 0)
                                 out.mass.emplace_back(part.global(ids[a]), part.global(ids[b]), Me(a, b));
                           }
                         });
  return out;
}

std::vector<std::pair<int, double>> solve_dirichlet_projection(DirichletPieces pieces) {
  // Sorted ids: the unknowns of the boundary system (a function may come from several pieces).
  std::vector<int> ids = pieces.functions;
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  const int nd = static_cast<int>(ids.size());
  std::vector<std::pair<int, double>> result;
  if (nd == 0) return result;
  // A function's row: by a table over the functions' numbers where it is smaller than the
  // triplets it serves (4 bytes a number against 16 a triplet: a volume, whose boundary faces
  // bring 81 triplets each at p = 2), else by a binary search per triplet (a planar domain,
  // whose boundary is a curve: the table would outweigh them).
  std::vector<int> row_of;
  if (static_cast<double>(ids.back()) + 1 <= 4.0 * static_cast<double>(pieces.mass.size())) {
    row_of.assign(static_cast<size_t>(ids.back()) + 1, -1);
    for (int k = 0; k < nd; ++k) row_of[ids[k]] = k;
  }
  auto index = [&](int f) {
    return row_of.empty() ? static_cast<int>(std::lower_bound(ids.begin(), ids.end(), f) - ids.begin()) : row_of[f];
  };
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(pieces.mass.size());
  for (const auto& t : pieces.mass) triplets.emplace_back(index(t.row()), index(t.col()), t.value());
  std::vector<Eigen::Triplet<double>>().swap(pieces.mass);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(nd);
  for (size_t k = 0; k < pieces.functions.size(); ++k) r[index(pieces.functions[k])] += pieces.load[k];
  Eigen::SparseMatrix<double> M(nd, nd);
  M.setFromTriplets(triplets.begin(), triplets.end());
  // A pivot tiny against its own diagonal entry is a dependent trace that round-off kept from
  // being an exact zero (B-spline mass matrices keep these ratios far above 1e-10 at any grading).
  // Small systems (a planar domain's boundary is a curve) by Eigen's simplicial LDL^T, whose
  // set-up costs nothing; from kSupernodalBoundary unknowns (a volume's boundary is a surface:
  // 26 000 at 64^3 cells, p = 2) by CHOLMOD's supernodal Cholesky, 0.5 s faster there.
  constexpr int kSupernodalBoundary = 4000;
  bool singular = false;
  Eigen::VectorXd x;
  if (nd < kSupernodalBoundary) {
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(M);
    singular = ldlt.info() != Eigen::Success;
    if (!singular) {
      const Eigen::VectorXd diagonal = ldlt.permutationP() * Eigen::VectorXd(M.diagonal());
      for (int k = 0; k < nd && !singular; ++k) singular = !(ldlt.vectorD()[k] > 1e-10 * diagonal[k]);
    }
    if (!singular) x = ldlt.solve(r);
  } else {
    SparseCholesky cholesky(Ordering::kAmd);
    const Eigen::SparseMatrix<double> lower = M.triangularView<Eigen::Lower>();
    try {
      cholesky.factorize(lower);
      const Eigen::VectorXd pivots = cholesky.pivots();
      for (int k = 0; k < nd && !singular; ++k) singular = !(pivots[k] > 1e-10 * M.coeff(k, k));
    } catch (const std::runtime_error&) {  // not positive definite
      singular = true;
    }
    if (!singular) x = cholesky.solve(r);
  }
  if (singular) throw std::runtime_error(
        "Dirichlet projection: the traces of the basis functions on the Dirichlet sides are linearly dependent, or "
        "nearly so in double precision (a pivot of the boundary mass matrix below 1e-10 of its diagonal); the space "
        "breaks the BezierMesh contract");
  result.reserve(nd);
  for (int k = 0; k < nd; ++k) result.emplace_back(ids[k], x[k]);
  return result;
}

Eigen::VectorXd project_dirichlet_data(const BezierMesh& mesh, const GeometryMap& geometry,
                                       const PoissonProblem& problem,
                                       const QuadratureOptions& quadrature, std::vector<bool>& fixed) {
  const int nf = mesh.num_functions();
  fixed.assign(nf, false);
  Eigen::VectorXd result = Eigen::VectorXd::Zero(nf);
  for (const auto& [f, value] :
       solve_dirichlet_projection(dirichlet_pieces(mesh, geometry, problem, quadrature, CellRange{}, MeshPart{}))) {
    fixed[f] = true;
    result[f] = value;
  }
  return result;
}

}  // namespace knotwork
