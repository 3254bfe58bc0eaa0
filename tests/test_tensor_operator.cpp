// The matrix-free Poisson operator of a tensor space (solver/tensor_operator): its products
// against the assembled matrix's, and properties that do not depend on either (constants in
// the kernel, the Dirichlet energy of the coordinate x equal to the domain's area).
#include <catch2/catch.hpp>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <omp.h>

#include <cmath>
#include <map>
#include <numeric>

#include "basis/core/input_error.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "cases/case_file.hpp"
#include "cases/spline_space.hpp"
#include "solver/poisson_solver.hpp"
#include "studies/pipeline.hpp"
#include "families/tensor/tensor_case.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/error_norms.hpp"
#include "solver/sparsity.hpp"
#include "solver/tensor_operator.hpp"

using namespace knotwork;

namespace {

struct Setup {
  CaseDescription c;
  TensorDiscretization d;
  std::unique_ptr<PatchGeometryMap> map;
  Eigen::VectorXd weights;
  // The net read in place, as the family's operator reads it (test_multigrid's copies it).
  TensorPatch patch() const {
    return {&d.space_u, &d.space_v, &weights, &d.geometry_u, &d.geometry_v, &d.geometry_homogeneous, true};
  }
};

std::unique_ptr<Setup> setup(const std::string& name, int p, int n) {
  auto s = std::make_unique<Setup>();
  s->c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
  patch_space(s->c).degree = {p, p};
  patch_space(s->c).elements_per_span = {n, n + 1};  // not square: u and v must not be mixed up
  s->d = build_tensor_discretization(s->c.geometry, patch_space(s->c));
  s->map = std::make_unique<PatchGeometryMap>(
      s->d.mesh, s->d.patch, PatchGeometryMap::ElementGrid{s->d.space_u.breakpoints(), s->d.space_v.breakpoints(), 0});
  if (s->d.mesh.is_rational()) s->weights = s->d.mesh.weights();
  return s;
}

// The assembled matrix over all functions (none fixed), lower triangle.
Eigen::SparseMatrix<double> assembled(const Setup& s, double reaction) {
  const int n = s.d.mesh.num_functions();
  const DofLayout layout = make_dof_layout(n, std::vector<bool>(n, false));
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(s.d.mesh, layout);
  PoissonForm form;
  form.reaction = reaction;
  form.load = false;
  Eigen::VectorXd rhs;
  assemble_poisson(s.d.mesh, *s.map, form, layout, Eigen::VectorXd::Zero(n), s.c.quadrature, K, rhs);
  return K;
}

double inf_norm(const Eigen::SparseMatrix<double>& lower) {
  const Eigen::SparseMatrix<double> whole = lower.selfadjointView<Eigen::Lower>();
  Eigen::VectorXd rows = Eigen::VectorXd::Zero(whole.rows());
  for (int k = 0; k < whole.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(whole, k); it; ++it) rows[it.row()] += std::abs(it.value());
  return rows.maxCoeff();
}

}  // namespace

TEST_CASE("Matrix-free tensor operator: products equal the assembled matrix's", "[tensor_operator]") {
  for (const char* name : {"square_sinsin", "quarter_annulus", "lshape"})
    for (int p : {2, 3, 5}) {
      const auto s = setup(name, p, 6);
      const double reaction = 0.7;
      const Eigen::SparseMatrix<double> K = assembled(*s, reaction);
      const TensorPoissonOperator A(s->patch(), 1.0, reaction);
      REQUIRE(A.num_functions() == K.rows());
      // The square's elements are squares (affine maps: the fast path), the annulus's are curved
      // (the geometry at every point); the L-shape patch's bilinear halves are not
      // parallelograms either, so both paths are compared with the matrix here.
      const long elements = long(s->d.elements_u) * s->d.elements_v;
      if (std::string(name) == "square_sinsin") REQUIRE(A.affine_elements() == elements);
      if (std::string(name) == "quarter_annulus") REQUIRE(A.affine_elements() == 0);
      // Every operator writes its matrix; only the square's map is one affine map, whose
      // Kronecker form also gives any row alone.
      REQUIRE(A.assembles_lower());
      REQUIRE(A.writes_rows() == (std::string(name) == "square_sinsin"));
      if (!A.writes_rows()) REQUIRE_THROWS_AS(A.row_entries(0, 0, nullptr, nullptr), std::logic_error);
      // Every tensor operator gives the pattern the mesh's cells give (some functions fixed).
      {
        std::vector<bool> fixed(K.rows(), false);
        for (size_t f = 0; f < fixed.size(); f += 7) fixed[f] = true;
        const DofLayout some = make_dof_layout(int(K.rows()), fixed);
        const Eigen::SparseMatrix<double> mesh_pattern = lower_pattern_matrix(s->d.mesh, some), own = A.lower_pattern(some);
        REQUIRE(A.gives_pattern());
        REQUIRE(own.nonZeros() == mesh_pattern.nonZeros());
        REQUIRE(std::equal(own.outerIndexPtr(), own.outerIndexPtr() + own.outerSize() + 1, mesh_pattern.outerIndexPtr()));
        REQUIRE(std::equal(own.innerIndexPtr(), own.innerIndexPtr() + own.nonZeros(), mesh_pattern.innerIndexPtr()));
      }
      const Eigen::VectorXd x = Eigen::VectorXd::Random(K.rows());
      const Eigen::VectorXd expected = K.selfadjointView<Eigen::Lower>() * x;
      Eigen::VectorXd y;
      A.apply(x, y);
      // Both are sums of the same products in other orders: each entry of K x sums at most
      // m = (2p+1)^2 entries, each of (p+1)^2 points per element over (p+1)^2 elements, with
      // a few operations per term; |error| <= gamma_m (|K| |x|) <= gamma_m ||K||_inf ||x||_inf.
      const double m = 8.0 * (2 * p + 1) * (2 * p + 1) * (p + 1) * (p + 1) * (p + 1) * (p + 1);
      const double bound = m * 2.2e-16 * inf_norm(K) * x.lpNorm<Eigen::Infinity>();
      INFO(name << ", p = " << p << ": |y - K x| = " << (y - expected).lpNorm<Eigen::Infinity>() << ", bound " << bound);
      REQUIRE((y - expected).lpNorm<Eigen::Infinity>() <= bound);
      const Eigen::VectorXd diagonal = A.diagonal();
      REQUIRE((diagonal - Eigen::VectorXd(K.diagonal())).lpNorm<Eigen::Infinity>() <=
              m * 2.2e-16 * K.diagonal().lpNorm<Eigen::Infinity>());
      // The same products on one thread (other bands, so other summation orders).
      const int threads = omp_get_max_threads();
      omp_set_num_threads(1);
      Eigen::VectorXd serial;
      A.apply(x, serial);
      omp_set_num_threads(threads);
      REQUIRE((serial - y).lpNorm<Eigen::Infinity>() <= bound);
    }
}

TEST_CASE("Matrix-free tensor operator: constants in the kernel, |grad x|^2 integrates to the area",
          "[tensor_operator]") {
  const double pi = std::acos(-1.0);
  const std::vector<std::pair<const char*, double>> domains = {
      {"square_sinsin", 1.0}, {"quarter_annulus", 3 * pi / 4}, {"lshape", 3.0}};
  for (const auto& [name, area] : domains)
    for (int p : {2, 4}) {
      const auto s = setup(name, p, 5);
      const TensorPoissonOperator A(s->patch(), 1.0, 0.0);
      const Eigen::VectorXd diagonal = A.diagonal();
      // The functions sum to 1 (B-splines, and NURBS R_a = w_a N_a / W), so K 1 = 0 up to
      // rounding in sums of about (p+1)^4 terms of size at most the diagonal.
      Eigen::VectorXd y;
      A.apply(Eigen::VectorXd::Ones(A.num_functions()), y);
      const double m = 8.0 * (2 * p + 1) * (2 * p + 1) * (p + 1) * (p + 1) * (p + 1) * (p + 1);
      INFO(name << ", p = " << p << ": |K 1| = " << y.lpNorm<Eigen::Infinity>());
      REQUIRE(y.lpNorm<Eigen::Infinity>() <= m * 2.2e-16 * diagonal.maxCoeff());
      // The space holds the geometry (isoparametric: the net is over the space's own basis and
      // weights), so x = sum_a (X_a / W_a) R_a exactly and x^T K x = int |grad x|^2 = area.
      REQUIRE(s->d.geometry_u.knots() == s->d.space_u.knots());
      REQUIRE(s->d.geometry_v.knots() == s->d.space_v.knots());
      const Eigen::VectorXd coordinate = s->d.geometry_homogeneous.col(0).cwiseQuotient(s->d.geometry_homogeneous.col(2));
      if (s->d.mesh.is_rational()) REQUIRE((s->weights - s->d.geometry_homogeneous.col(2)).norm() == 0);
      A.apply(coordinate, y);
      INFO("x^T K x = " << coordinate.dot(y) << ", relative error " << std::abs(coordinate.dot(y) - area) / area);
      // Gauss rules of p + 1 points: exact for the square's and the L-shape's polynomial maps;
      // the annulus's rational integrand to the rule's error (measured 4.6e-10 relative at p = 2
      // and 4e-16 at p = 4 on 5 x 6 elements).
      REQUIRE(std::abs(coordinate.dot(y) - area) <= (std::string(name) == "quarter_annulus" ? 1e-8 : 1e-12) * area);
    }
}

// Through the pipeline ([solver] matrix = "matrix_free"): no matrix, the load, the Dirichlet
// lifting and Neumann terms from the operator and the assembly's boundary code; the solution
// must be the assembled CG's to what the two backward errors allow.
TEST_CASE("Matrix-free CG solves what assembled CG solves", "[tensor_operator][solver]") {
  for (const auto& [name, p] : std::vector<std::pair<const char*, int>>{{"square_exp_sin", 3}, {"quarter_annulus", 2}, {"lshape", 4}}) {
    CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
    patch_space(c).degree = {p, p};
    c.solver.method = "iterative";
    const auto space = build_space(c);
    // kappa_inf(K) over the free dofs, from the assembled matrix made dense (a few hundred dofs).
    double kappa = 0;
    {
      PoissonSolveOptions o;
      o.compute_errors = false;
      o.on_system = [&](const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXd&) {
        const Eigen::MatrixXd K = Eigen::MatrixXd(Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>()));
        const Eigen::MatrixXd inverse = K.inverse();
        kappa = K.cwiseAbs().rowwise().sum().maxCoeff() * inverse.cwiseAbs().rowwise().sum().maxCoeff();
      };
      solve_poisson(space->mesh(), space->geometry(), c.problem, o);
    }
    REQUIRE(kappa > 0);
    c.solver.matrix = "assembled";
    SolverReport assembled_report, free_report;
    const PoissonSolution assembled = solve_case(c, *space, Ordering::kAmd, {}, &assembled_report);
    c.solver.matrix = "matrix_free";
    const PoissonSolution free = solve_case(c, *space, Ordering::kAmd, {}, &free_report);
    REQUIRE_FALSE(assembled_report.matrix_free);
    REQUIRE(free_report.matrix_free);
    REQUIRE(free.matrix_nonzeros == 0);
    REQUIRE(assembled.iterative.converged);
    REQUIRE(free.iterative.converged);
    // Each solves K x = b to a backward error <= tol, so each is within about 2 kappa tol of the
    // exact solution (relative, infinity norm; first order, kappa tol << 1).
    const double tol = c.solver.tolerance, scale = assembled.coefficients.lpNorm<Eigen::Infinity>();
    const double difference = (free.coefficients - assembled.coefficients).lpNorm<Eigen::Infinity>();
    INFO(name << ", p = " << p << ": kappa " << kappa << ", |x_free - x_assembled| / |x| = " << difference / scale);
    REQUIRE(kappa * tol < 1e-3);
    REQUIRE(difference <= 4 * kappa * tol * scale);
    REQUIRE(std::abs(free.errors->h1_semi - assembled.errors->h1_semi) <= 1e-6 * assembled.errors->h1_semi);
  }
}

// Affine elements with different factors (a map stretched twice as much right of a C^0 kink):
// element by element, not the Kronecker form of a uniformly affine patch (the unit square's
// above). Checked by what depends on neither: K 1 = 0, and the coordinates x and y, both in
// the space, with x^T K x and y^T K y the domain's area.
TEST_CASE("Matrix-free tensor operator: affine elements with different factors", "[tensor_operator]") {
  const BSplineBasis1D u(2, {0, 0, 0, 0.25, 0.5, 0.5, 0.75, 1, 1, 1}), v = BSplineBasis1D::open_uniform(2, 0, 1, 3);
  const int nu = u.num_functions(), nv = v.num_functions();
  auto kinked = [](double t) { return t <= 0.5 ? t : 0.5 + 2 * (t - 0.5); };  // x in [0, 1.5]
  Eigen::MatrixX3d net(long(nu) * nv, 3);
  Eigen::VectorXd x(net.rows()), y(net.rows());
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      // Greville abscissae: linear functions (and, at the double knot, the kink) are reproduced.
      const double gu = (u.knots()[i + 1] + u.knots()[i + 2]) / 2, gv = (v.knots()[j + 1] + v.knots()[j + 2]) / 2;
      x[i + nu * j] = kinked(gu), y[i + nu * j] = gv;
      net.row(i + long(nu) * j) << x[i + nu * j], y[i + nu * j], 1.0;
    }
  const Eigen::VectorXd none;
  const TensorPoissonOperator A({&u, &v, &none, &u, &v, &net}, 1.0, 0.0);
  REQUIRE(A.all_elements_affine());
  REQUIRE_FALSE(A.uniform_factors());
  Eigen::VectorXd k;
  A.apply(Eigen::VectorXd::Ones(A.num_functions()), k);
  REQUIRE(k.lpNorm<Eigen::Infinity>() <= 8.0 * 25 * 81 * 2.2e-16 * A.diagonal().maxCoeff());
  for (const Eigen::VectorXd* c : {&x, &y}) {
    A.apply(*c, k);
    INFO("x^T K x = " << c->dot(k));
    // Exact rules on affine elements: rounding only, in n sums of m terms of at most
    // |c|_inf^2 max|K_ij| (and |K_ij| <= max diagonal: K is positive semi-definite).
    const double m = 8.0 * 25 * 81, bound = m * 2.2e-16 * c->size() * c->squaredNorm() * A.diagonal().maxCoeff();
    REQUIRE(std::abs(c->dot(k) - 1.5) <= bound);
  }
  // The unit square's elements share one set of factors.
  const BSplineBasis1D s = BSplineBasis1D::open_uniform(3, 0, 1, 4);
  const std::vector<double> xi = greville_abscissae(s);
  Eigen::MatrixX3d square(49, 3);
  for (int j = 0; j < 7; ++j)
    for (int i = 0; i < 7; ++i) square.row(i + 7 * j) << xi[i], xi[j], 1.0;
  REQUIRE(TensorPoissonOperator({&s, &s, &none, &s, &s, &square}, 1.0, 0.0).uniform_factors());
  // Decided from the net (its points are the map at the Greville abscissae). The last control
  // point's function lives on the four elements of the far corner: moved by 1e-9, far above
  // the 64 eps the data's rounding allows, it bends them while the first element stays affine,
  // and the operator is not uniform (nor affine: those are curved). Moved by 4 ulp it still is.
  Eigen::MatrixX3d bent = square;
  bent(48, 0) += 1e-9;
  const TensorPoissonOperator B({&s, &s, &none, &s, &s, &bent}, 1.0, 0.0);
  REQUIRE_FALSE(B.uniform_factors());
  REQUIRE_FALSE(B.all_elements_affine());
  Eigen::MatrixX3d rounded = square;
  rounded(48, 0) += 4 * 2.2e-16;
  REQUIRE(TensorPoissonOperator({&s, &s, &none, &s, &s, &rounded}, 1.0, 0.0).uniform_factors());
}

// The error norms by sum factorization against error_norms' cell-by-cell ones, on the same
// coefficients and rule: the same sums of the same integrand, evaluated in other orders. u_h
// and its gradient differ by rounding, |d u_h| <= g eps (p+1)^2 |c|_inf and |d grad u_h| <= that
// times the largest |grad R_a| (<= 2 p n / L for n elements over a side of length at least L:
// 1 on these domains), so each norm moves by at most that times sqrt(area) (g = 64 for the
// sums' lengths).
TEST_CASE("Matrix-free error norms equal the cell-by-cell ones", "[tensor_operator]") {
  for (const char* name : {"square_sinsin", "quarter_annulus", "lshape"})
    for (int p : {2, 3}) {
      const auto s = setup(name, p, 6);
      const TensorPoissonOperator A(s->patch(), 1.0, 0.0);
      // A discrete function far from u (errors of order one) and the Galerkin solution (the
      // discretization's errors): both sizes of error.
      CaseDescription direct_case = s->c;
      direct_case.solver.method = "direct";
      const auto space = build_space(direct_case);
      const Eigen::VectorXd solution = solve_case(direct_case, *space, Ordering::kAmd).coefficients;
      for (const Eigen::VectorXd& c : {Eigen::VectorXd(Eigen::VectorXd::Random(A.num_functions())), solution}) {
      const ExactSolution& exact = *s->c.problem.exact;
      std::array<double, 2> squares{};
      Eigen::VectorXd per_cell;
      REQUIRE(A.squared_errors(c, exact, s->c.quadrature.error_points_u, s->c.quadrature.error_points_v, squares, &per_cell));
      Eigen::VectorXd expected_cells;
      const ErrorNorms expected = error_norms(s->d.mesh, *s->map, c, exact, s->c.quadrature, &expected_cells);
      const double n = std::max(s->d.elements_u, s->d.elements_v), area = 3.0;  // (the largest area here)
      const double value = 64 * 2.2e-16 * (p + 1) * (p + 1) * c.lpNorm<Eigen::Infinity>();
      const double l2_bound = value * std::sqrt(area), h1_bound = value * (1 + 2 * p * n) * std::sqrt(area);
      INFO(name << ", p = " << p << ": L2 " << std::sqrt(squares[0]) << " against " << expected.l2 << ", H1 "
                << std::sqrt(squares[1]) << " against " << expected.h1_semi);
      REQUIRE(std::abs(std::sqrt(squares[0]) - expected.l2) <= l2_bound);
      REQUIRE(std::abs(std::sqrt(squares[1]) - expected.h1_semi) <= h1_bound);
      REQUIRE(per_cell.size() == s->d.mesh.num_cells());
      for (Eigen::Index k = 0; k < per_cell.size(); ++k)
        REQUIRE(std::abs(std::sqrt(per_cell[k]) - std::sqrt(expected_cells[k])) <= h1_bound);
      }
    }
}

// A sheared patch (x = u + v / 2, y = v on graded knots): one affine map with d12 != 0, so
// the Kronecker form's mixed terms are used (the unit square's d12 is 0). Checked by what does
// not depend on it: the coordinates are in the space, with int |grad x|^2 = int |grad y|^2 =
// area = 1 and int grad x . grad y = 0; K 1 = 0; with a reaction c, 1^T K 1 = c area.
TEST_CASE("Matrix-free tensor operator: the Kronecker form's mixed terms on a sheared patch", "[tensor_operator]") {
  const BSplineBasis1D u(3, {0, 0, 0, 0, 0.1, 0.3, 0.6, 1, 1, 1, 1}), v(3, {0, 0, 0, 0, 0.2, 0.5, 0.7, 0.9, 1, 1, 1, 1});
  const int nu = u.num_functions(), nv = v.num_functions();
  const std::vector<double> xi = greville_abscissae(u), eta = greville_abscissae(v);
  Eigen::MatrixX3d net(long(nu) * nv, 3);
  Eigen::VectorXd x(net.rows()), y(net.rows());
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const long k = i + long(nu) * j;
      x[k] = xi[i] + 0.5 * eta[j], y[k] = eta[j];
      net.row(k) << x[k], y[k], 1.0;
    }
  const Eigen::VectorXd none;
  for (const double reaction : {0.0, 2.0}) {
    const TensorPoissonOperator A({&u, &v, &none, &u, &v, &net}, 1.0, reaction);
    REQUIRE(A.uniform_factors());
    REQUIRE(A.factors()[1] != 0);
    // Rounding only: n sums of (2p+1)^2 terms of at most |c|_inf^2 max diagonal (K is
    // positive semi-definite), as above.
    const double m = 8.0 * 49 * 256, bound = m * 2.2e-16 * x.size() * 2.25 * A.diagonal().maxCoeff();
    Eigen::VectorXd kx, ky, k1;
    A.apply(x, kx);
    A.apply(y, ky);
    A.apply(Eigen::VectorXd::Ones(x.size()), k1);
    INFO("reaction " << reaction << ": x^T K x " << x.dot(kx) << ", y^T K y " << y.dot(ky) << ", x^T K y " << x.dot(ky)
                     << ", 1^T K 1 " << k1.sum());
    if (reaction == 0) {
      REQUIRE(std::abs(x.dot(kx) - 1) <= bound);
      REQUIRE(std::abs(y.dot(ky) - 1) <= bound);
      REQUIRE(std::abs(x.dot(ky)) <= bound);
      REQUIRE(k1.lpNorm<Eigen::Infinity>() <= m * 2.2e-16 * A.diagonal().maxCoeff());
    } else {
      REQUIRE(std::abs(k1.sum() - reaction) <= bound);
    }
    // The same identities from the matrix written from the Kronecker form, all functions free.
    REQUIRE(A.assembles_lower());
    const Eigen::SparseMatrix<double> lower = A.lower_matrix(make_dof_layout(int(x.size()), std::vector<bool>(x.size(), false)));
    const Eigen::SparseMatrix<double> K = lower.selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd one = Eigen::VectorXd::Ones(x.size());
    if (reaction == 0) {
      REQUIRE(std::abs(x.dot(K * x) - 1) <= bound);
      REQUIRE(std::abs(y.dot(K * y) - 1) <= bound);
      REQUIRE(std::abs(x.dot(K * y)) <= bound);
      REQUIRE((K * one).lpNorm<Eigen::Infinity>() <= m * 2.2e-16 * A.diagonal().maxCoeff());
    } else {
      REQUIRE(std::abs(one.dot(K * one) - reaction) <= bound);
    }
    // Rows of a box from a vector given on the interior functions: the whole product's rows.
    const TensorPoissonOperator::FunctionBox free{1, nu - 2, 1, nv - 2}, rows{2, 3, 1, 4};
    Eigen::VectorXd inner(long(free.count_u) * free.count_v), whole = Eigen::VectorXd::Zero(x.size()), all;
    for (int j = 0; j < free.count_v; ++j)
      for (int i = 0; i < free.count_u; ++i)
        whole[(1 + i) + long(nu) * (1 + j)] = inner[i + long(free.count_u) * j] = x[(1 + i) + long(nu) * (1 + j)];
    A.apply(whole, all);
    Eigen::VectorXd r(long(rows.count_u) * rows.count_v);
    A.apply_rows(inner.data(), free, rows, r.data());
    for (int j = 0; j < rows.count_v; ++j)
      for (int i = 0; i < rows.count_u; ++i)
        REQUIRE(std::abs(r[i + long(rows.count_u) * j] - all[(rows.first_u + i) + long(nu) * (rows.first_v + j)]) <= bound);
  }
}

namespace {

// The lower triangle and load that solve_poisson factors, captured through on_system, with the
// element loop or with the operator's matrix.
struct System {
  Eigen::SparseMatrix<double> K;
  Eigen::VectorXd F, coefficients;
};

System solved_system(const Setup& s, double reaction, bool from_operator) {
  PoissonProblem problem = s.c.problem;
  problem.reaction = reaction;
  PoissonSolveOptions options;
  options.quadrature = s.c.quadrature;
  options.compute_errors = false;
  System out;
  options.on_system = [&out](const Eigen::SparseMatrix<double>& K, const Eigen::VectorXd& F) { out.K = K, out.F = F; };
  bool asked = false;
  if (from_operator)
    options.matrix_from_operator = [&s, &asked, reaction] {
      asked = true;
      return std::make_shared<const TensorPoissonOperator>(s.patch(), 1.0, reaction);
    };
  out.coefficients = solve_poisson(s.d.mesh, *s.map, problem, options).coefficients;
  REQUIRE(asked == from_operator);
  return out;
}

// The element loop's system against one whose matrix the operator wrote: the same pattern
// (functions that share a cell, Dirichlet functions left out); each entry within
// m sqrt(K_aa K_bb), m = 8 (p+1)^4 eps (entry (a, b) sums, over at most (p+1)^2 cells of (p+1)^2
// points, terms whose absolute sum is at most sqrt(K_aa K_bb) by Cauchy-Schwarz, the integrand
// being positive semi-definite; a few roundings per term on either side); and the other
// system's solution solving the element loop's to a backward error of rounding size (both by
// Eigen's LDL^T, not the CHOLMOD of the runs). Returns m.
double require_same_system(const System& loop, const System& other, int p) {
  const Eigen::SparseMatrix<double>&A = loop.K, &B = other.K;
  REQUIRE(A.rows() == B.rows());
  REQUIRE(A.nonZeros() == B.nonZeros());
  REQUIRE(std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1, B.outerIndexPtr()));
  REQUIRE(std::equal(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros(), B.innerIndexPtr()));
  const double m = 8.0 * std::pow(p + 1, 4) * 2.2e-16;
  for (int k = 0; k < A.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator a(A, k), b(B, k); a; ++a, ++b)
      REQUIRE(std::abs(a.value() - b.value()) <= m * std::sqrt(A.coeff(a.row(), a.row()) * A.coeff(k, k)));
  const Eigen::SparseMatrix<double> whole = A.selfadjointView<Eigen::Lower>();
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(B);
  REQUIRE(ldlt.info() == Eigen::Success);
  const Eigen::VectorXd x = ldlt.solve(other.F);
  const double backward = (whole * x - loop.F).lpNorm<Eigen::Infinity>() /
                          (inf_norm(A) * x.lpNorm<Eigen::Infinity>() + loop.F.lpNorm<Eigen::Infinity>());
  INFO("backward error " << backward);
  REQUIRE(backward <= m * (2 * p + 1) * (2 * p + 1));
  return m;
}

}  // namespace

// The matrix written from the Kronecker form (solver/tensor_operator_matrix.cpp) against the
// element loop's, as solve_poisson factors them: the same pattern (functions that share a cell,
// Dirichlet functions left out), entries and load equal to rounding, and each solution a
// solution of the other system to a backward error of rounding size.
TEST_CASE("The matrix from the Kronecker form is the element loop's", "[tensor_operator][solver]") {
  for (const int continuity : {-1, 0})  // C^{p-1}, and C^0 lines: neighbours in index that share no cell
    for (int p : {2, 3, 5}) {
      const auto s = [&] {
        auto c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/square_sinsin.toml");
        patch_space(c).degree = {p, p};
        patch_space(c).elements_per_span = {5, 6};
        patch_space(c).continuity = {continuity, continuity};
        auto setup = std::make_unique<Setup>();
        setup->c = c;
        setup->d = build_tensor_discretization(c.geometry, patch_space(c));
        setup->map = std::make_unique<PatchGeometryMap>(setup->d.mesh, setup->d.patch,
                                                        PatchGeometryMap::ElementGrid{setup->d.space_u.breakpoints(),
                                                                                      setup->d.space_v.breakpoints(), 0});
        if (setup->d.mesh.is_rational()) setup->weights = setup->d.mesh.weights();
        return setup;
      }();
      for (const double reaction : {0.0, 0.7}) {
        REQUIRE(TensorPoissonOperator(s->patch(), 1.0, reaction).assembles_lower());
        const System loop = solved_system(*s, reaction, false), kron = solved_system(*s, reaction, true);
        INFO("p = " << p << ", continuity " << continuity << ", reaction " << reaction);
        const double m = require_same_system(loop, kron, p);
        // The load: f R_a by the same rule, and the lifting K g of the Dirichlet values: sums of
        // at most (2p+1)^2 (p+1)^4 terms, each bounded by |F|_inf and |K|_inf |g|_inf.
        const double load_bound = m * (2 * p + 1) * (2 * p + 1) *
                                  (loop.F.lpNorm<Eigen::Infinity>() + inf_norm(loop.K) * loop.coefficients.lpNorm<Eigen::Infinity>());
        REQUIRE((loop.F - kron.F).lpNorm<Eigen::Infinity>() <= load_bound);
      }
    }
}

// The same comparison where the operator writes the matrix by sum factorization
// (solver/tensor_operator_sum_factorized.cpp): curved maps with the NURBS space and with
// B-splines on the same exact map, and a piecewise-affine map (the L-shape), against the
// element loop, which integrates each cell's element matrix by itself.
TEST_CASE("The matrix by sum factorization is the element loop's", "[tensor_operator][solver]") {
  struct Variant {
    const char* name;
    bool rational;
  };
  for (const Variant variant : {Variant{"quarter_annulus", true}, Variant{"quarter_annulus", false}, Variant{"lshape", false}})
    for (const int continuity : {-1, 0})
      for (int p : {2, 3, 5}) {
        auto s = setup(variant.name, p, 5);
        if (continuity == 0 || !variant.rational) {
          patch_space(s->c).continuity = {continuity, continuity};
          patch_space(s->c).rational = variant.rational;
          s->d = build_tensor_discretization(s->c.geometry, patch_space(s->c));
          s->map = std::make_unique<PatchGeometryMap>(
              s->d.mesh, s->d.patch, PatchGeometryMap::ElementGrid{s->d.space_u.breakpoints(), s->d.space_v.breakpoints(), 0});
          s->weights = s->d.mesh.is_rational() ? s->d.mesh.weights() : Eigen::VectorXd();
        }
        REQUIRE(s->d.mesh.is_rational() == (variant.rational && std::string(variant.name) == "quarter_annulus"));
        for (const double reaction : {0.0, 0.7}) {
          const TensorPoissonOperator op(s->patch(), 1.0, reaction);
          REQUIRE(op.assembles_lower());
          REQUIRE_FALSE(op.writes_rows());  // (not the Kronecker form: no row alone)
          const System loop = solved_system(*s, reaction, false), summed = solved_system(*s, reaction, true);
          INFO(variant.name << (variant.rational ? " (NURBS)" : "") << ", p = " << p << ", continuity " << continuity
                            << ", reaction " << reaction);
          const double m = require_same_system(loop, summed, p);
          // The operator's load and lifting against the element loop's, bounded as above.
          REQUIRE((loop.F - summed.F).lpNorm<Eigen::Infinity>() <=
                  m * (2 * p + 1) * (2 * p + 1) *
                      (loop.F.lpNorm<Eigen::Infinity>() + inf_norm(loop.K) * loop.coefficients.lpNorm<Eigen::Infinity>()));
        }
      }
}

// A folded map is refused by the sum factorization in the element loop's words: the lowest
// cell where det J <= 0.
TEST_CASE("The sum-factorized matrix refuses a folded map, naming the cell", "[tensor_operator]") {
  auto s = setup("quarter_annulus", 2, 4);
  // Mirror the net in x: the map turns clockwise, det J < 0 everywhere (cell 0 is named).
  s->d.geometry_homogeneous.col(0) *= -1;
  const TensorPoissonOperator op(s->patch(), 1.0, 0.0);
  const int n = op.num_functions();
  const DofLayout all = make_dof_layout(n, std::vector<bool>(n, false));
  REQUIRE_THROWS_AS(op.lower_matrix(all), GeometryError);
  using Catch::Matchers::Contains;
  using Catch::Matchers::EndsWith;
  using Catch::Matchers::StartsWith;
  REQUIRE_THROWS_WITH(op.lower_matrix(all), StartsWith("geometry has a non-positive Jacobian (det J = -") &&
                                                Contains("at a quadrature point of cell 0 (u in [0, 0.25], v in [0, 0.2])") &&
                                                EndsWith("the map folds over or is oriented clockwise"));
}

namespace {

// check(ranks, rank, part) on every part of c's space on 2 and 3 processes
// (SpaceFamily::build_part), each one a part indeed.
template <class Check>
void for_each_part(const CaseDescription& c, Check check) {
  const SpaceFamily& family = space_family(c);
  for (const int ranks : {2, 3})
    for (int rank = 0; rank < ranks; ++rank) {
      INFO(ranks << " processes, rank " << rank);
      const std::unique_ptr<SplineSpace> part = family.build_part(c, 0, rank, ranks, {});
      REQUIRE(part->part());
      check(ranks, rank, *part);
    }
}

// A part's free dofs with every `period`-th global function fixed (from `offset`), each free
// dof's global row numbered past the fixed functions below it, and the owned rows' range.
struct PartRows {
  DofLayout layout;
  std::vector<int> global_row;
  int first_row = 0, last_row = 0;
};

PartRows part_rows(const MeshPart& share, int num_functions, int period, int offset) {
  std::vector<bool> fixed(num_functions);
  for (int f = 0; f < num_functions; ++f) fixed[f] = share.global(f) % period == offset;
  PartRows r;
  r.layout = make_dof_layout(num_functions, fixed);
  const auto row_of = [&](int g) { return g - (g + period - 1 - offset) / period; };  // fixed ones below g
  for (int d = 0; d < r.layout.num_free(); ++d) r.global_row.push_back(row_of(share.global(r.layout.function_of_dof[d])));
  r.first_row = row_of(share.first_owned_function), r.last_row = row_of(share.last_owned_function);
  return r;
}

void require_same_owned_rows(const RankRows& a, const RankRows& b) {
  REQUIRE(a.first == b.first);
  REQUIRE(a.last == b.last);
  REQUIRE(a.owned.diagonal_start == b.owned.diagonal_start);
  REQUIRE(a.owned.diagonal_cols == b.owned.diagonal_cols);
  REQUIRE(a.owned.off_start == b.owned.off_start);
  REQUIRE(a.owned.off_cols == b.owned.off_cols);
}

}  // namespace

// Under mpirun each process writes its owned rows of the matrix, whole, from the operator of
// its part of the patch (SpaceFamily::build_part), and their load (solver/poisson_solver.cpp):
// here every row of every part on 2 and 3 processes against the whole patch's element loop.
// The case (tests/mpi/tensor_affine_rows.toml) shears (a mixed term), has a reaction, a C^0
// knot and an extra knot where row boundaries fall.
TEST_CASE("A part's operator writes its owned rows of the whole matrix", "[tensor_operator][solver]") {
  const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/tests/mpi/tensor_affine_rows.toml");
  const SpaceFamily& family = space_family(c);
  const std::unique_ptr<SplineSpace> whole = family.build(c, 0, {});
  const int n = whole->mesh().num_functions();
  const DofLayout all_free = make_dof_layout(n, std::vector<bool>(n, false));
  Eigen::SparseMatrix<double> lower = lower_pattern_matrix(whole->mesh(), all_free);
  Eigen::VectorXd F;
  const PoissonForm form = poisson_form(c.problem);
  REQUIRE(form.reaction == 2.0);
  assemble_poisson(whole->mesh(), whole->geometry(), form, all_free, Eigen::VectorXd::Zero(n), c.quadrature, lower, F);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> K = lower.selfadjointView<Eigen::Lower>();
  // As in the test above, p = 3 the larger degree.
  const int p = 3;
  const double m = 8.0 * std::pow(p + 1, 4) * 2.2e-16, load_bound = m * (2 * p + 1) * (2 * p + 1) * F.lpNorm<Eigen::Infinity>();
  for_each_part(c, [&](int, int, const SplineSpace& space) {
      const SplineSpace* part = &space;
      const MeshPart& share = *part->part();
      REQUIRE(part->mesh().num_cells() < whole->mesh().num_cells());
      const std::unique_ptr<MatrixFreePoisson> op = part->matrix_free_operator(1.0, c.problem.reaction, c.quadrature);
      REQUIRE(op);
      REQUIRE(op->num_functions() == part->mesh().num_functions());
      REQUIRE(op->writes_rows());
      const Eigen::VectorXd load = op->load(c.problem.source);
      std::vector<int> columns(part->mesh().num_functions());
      std::iota(columns.begin(), columns.end(), 0);
      std::vector<double> row(columns.size());
      int owned = 0;
      for (int f = 0; f < part->mesh().num_functions(); ++f) {
        const int g = share.global(f);
        if (g < share.first_owned_function || g >= share.last_owned_function) continue;
        ++owned;
        op->row_entries(f, int(columns.size()), columns.data(), row.data());
        // Every entry of the whole row is among the part's functions, and equal to rounding.
        int found = 0;
        for (int h = 0; h < int(columns.size()); ++h) {
          const double expected = K.coeff(g, share.global(h));
          found += K.coeff(g, share.global(h)) != 0 || std::abs(row[h]) > 0 ? 1 : 0;
          INFO("row " << g << ", column " << share.global(h) << ": " << row[h] << " against " << expected);
          REQUIRE(std::abs(row[h] - expected) <= m * std::sqrt(K.coeff(g, g) * K.coeff(share.global(h), share.global(h))));
        }
        REQUIRE(found == K.row(g).nonZeros());
        INFO("load of " << g << ": " << load[f] << " against " << F[g]);
        REQUIRE(std::abs(load[f] - F[g]) <= load_bound);
      }
      REQUIRE(owned == share.last_owned_function - share.first_owned_function);
      // The owned rows' pattern from the operator's couplings is the one the mesh's cells give,
      // with every seventh global function fixed (rows numbered past the fixed ones).
      const PartRows p = part_rows(share, part->mesh().num_functions(), 7, 3);
      const RankRows from_mesh = rank_rows_pattern(part->mesh(), p.layout, p.global_row, p.first_row, p.last_row, share.owned);
      const RankRows from_operator = owned_rows_pattern(p.layout, p.global_row, p.first_row, p.last_row,
                                                        [&op](int f, std::vector<int>& out) { op->coupled_functions(f, out); });
      require_same_owned_rows(from_operator, from_mesh);
      REQUIRE(from_operator.halo_start.back() == 0);  // nothing to send
    });
}

// On a curved patch a process's owned rows come from its part's matrix by sum factorization
// (over the part's element rows, which hold every element of an owned function): every owned
// row of every part on 2 and 3 processes against the whole patch's element loop, on the
// quarter annulus's NURBS space with a reaction, and on a patch with Dirichlet and Neumann sides,
// a C^0 knot and an extra knot among the row boundaries. On several patches (the plus, the
// plate with a hole: NURBS) a part holds whole patches and a neighbour's cells along its
// interfaces: its operator glues the patches it holds, whole.
TEST_CASE("A part's matrix by sum factorization holds its owned rows whole", "[tensor_operator][solver]") {
  for (const std::string path : {std::string(KNOTWORK_SOURCE_DIR) + "/cases/quarter_annulus.toml",
                                 std::string(KNOTWORK_SOURCE_DIR) + "/tests/mpi/tensor_mixed_conditions.toml",
                                 std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_plus.toml",
                                 std::string(KNOTWORK_SOURCE_DIR) + "/cases/multipatch_plate_with_hole.toml"}) {
    CaseDescription c = load_case(path);
    c.problem.reaction = 0.7;
    const SpaceFamily& family = space_family(c);
    const std::unique_ptr<SplineSpace> whole = family.build(c, 0, {});
    const int n = whole->mesh().num_functions();
    const DofLayout all_free = make_dof_layout(n, std::vector<bool>(n, false));
    Eigen::SparseMatrix<double> lower = lower_pattern_matrix(whole->mesh(), all_free);
    Eigen::VectorXd F;
    PoissonForm form = poisson_form(c.problem);
    form.load = false;
    assemble_poisson(whole->mesh(), whole->geometry(), form, all_free, Eigen::VectorXd::Zero(n), c.quadrature, lower, F);
    const Eigen::SparseMatrix<double, Eigen::RowMajor> K = lower.selfadjointView<Eigen::Lower>();
    const int p = std::max(whole->degree()[0], whole->degree()[1]);
    const double m = 8.0 * std::pow(p + 1, 4) * 2.2e-16;
    // (A case of fewer patches than processes is built whole on each: no part to check.)
    const auto parts = [&](auto check) {
      for (const int ranks : {2, 3})
        for (int rank = 0; rank < ranks; ++rank) {
          const std::unique_ptr<SplineSpace> space = family.build_part(c, 0, rank, ranks, {});
          if (!space->part()) {
            REQUIRE((c.multipatch() && c.domain.num_patches() < ranks));
            continue;
          }
          check(ranks, rank, *space);
        }
    };
    parts([&](int ranks, int rank, const SplineSpace& space) {
      const MeshPart& share = *space.part();
      const std::unique_ptr<MatrixFreePoisson> op = space.matrix_free_operator(1.0, c.problem.reaction, c.quadrature);
      REQUIRE(op);
      REQUIRE(op->assembles_lower());
      REQUIRE_FALSE(op->writes_rows());
      REQUIRE(op->gives_pattern());
      const int local = space.mesh().num_functions();
      const Eigen::SparseMatrix<double> part_lower = op->lower_matrix(make_dof_layout(local, std::vector<bool>(local, false)));
      const Eigen::SparseMatrix<double, Eigen::RowMajor> Kp = part_lower.selfadjointView<Eigen::Lower>();
      int owned = 0;
      for (int f = 0; f < local; ++f) {
        const int g = share.global(f);
        if (g < share.first_owned_function || g >= share.last_owned_function) continue;
        ++owned;
        INFO(path << ": " << ranks << " processes, rank " << rank << ", row " << g);
        REQUIRE(Kp.row(f).nonZeros() == K.row(g).nonZeros());
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(Kp, f); it; ++it) {
          const int h = share.global(int(it.col()));
          REQUIRE(std::abs(it.value() - K.coeff(g, h)) <= m * std::sqrt(K.coeff(g, g) * K.coeff(h, h)));
        }
      }
      REQUIRE(owned == share.last_owned_function - share.first_owned_function);
    });
  }
}

// Where the map is affine on some processes' rows only, those write their rows from the
// Kronecker form and the others by sum factorization (tests/mpi/tensor_half_affine.toml checks
// the solve).
TEST_CASE("A part's operator writes rows only where its own rows are affine", "[tensor_operator]") {
  const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/tests/mpi/tensor_half_affine.toml");
  const SpaceFamily& family = space_family(c);
  const auto writes = [&](int rank, int ranks) {
    return family.build_part(c, 0, rank, ranks, {})->matrix_free_operator(1.0, 0.0, c.quadrature)->writes_rows();
  };
  REQUIRE(writes(0, 2));
  REQUIRE_FALSE(writes(1, 2));
  // Serially the whole patch's matrix is written by sum factorization, rows alone are not.
  // (The space outlives its operator, which reads the space's net in place.)
  const std::unique_ptr<SplineSpace> space = family.build(c, 0, {});
  const std::unique_ptr<MatrixFreePoisson> whole = space->matrix_free_operator(1.0, 0.0, c.quadrature);
  REQUIRE(whole->assembles_lower());
  REQUIRE_FALSE(whole->writes_rows());
}

// Refining a polynomial patch (equal weights) keeps it polynomial: by the partition of unity
// the refined weights are the same constant, exactly. Computed by the refinement, they drifted
// by 67 eps at degree 4 and 1000 elements (the drift grows with the knots inserted), and the
// unit square passed for a rational patch: no Kronecker form, the slower rational kernels.
// And elements 1000 times shorter along u than along v are affine: their Jacobian's rounding
// is judged by their shorter side.
TEST_CASE("A polynomial patch stays polynomial however finely it is refined", "[tensor_operator]") {
  CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/square_sinsin.toml");
  for (const int p : {3, 4, 5}) {
    INFO("degree " << p);
    patch_space(c).degree = {p, p};
    patch_space(c).elements_per_span = {1000, 3};
    const std::unique_ptr<SplineSpace> space = space_family(c).build(c, 0, {});
    if (space->mesh().is_rational()) REQUIRE((space->mesh().weights().array() == 1.0).all());
    const std::unique_ptr<MatrixFreePoisson> op = space->matrix_free_operator(1.0, 0.0, c.quadrature);
    REQUIRE(op);
    REQUIRE(op->writes_rows());  // the Kronecker form's
  }
}

// Where the element loop fills a process's rows (a curved patch), their pattern still comes
// from its part's operator (its couplings, from the univariate bases), the halo's from the
// process's cells: the same rows as the walk over the mesh's cells gives, on every part of 2 and
// 3 processes, a C^0 knot and an extra knot among the row boundaries, every fifth function fixed.
TEST_CASE("A part's operator gives its owned rows' pattern on a curved patch", "[tensor_operator]") {
  const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/tests/mpi/tensor_mixed_conditions.toml");
  for_each_part(c, [&](int, int, const SplineSpace& space) {
      const SplineSpace* part = &space;
      const MeshPart& share = *part->part();
      const std::unique_ptr<MatrixFreePoisson> op = part->matrix_free_operator(1.0, 0.0, c.quadrature);
      REQUIRE(op);
      REQUIRE_FALSE(op->writes_rows());
      REQUIRE(op->gives_pattern());
      const PartRows p = part_rows(share, part->mesh().num_functions(), 5, 1);
      const CoupledFunctions coupled = [&op](int f, std::vector<int>& out) { op->coupled_functions(f, out); };
      const RankRows walked = rank_rows_pattern(part->mesh(), p.layout, p.global_row, p.first_row, p.last_row, share.owned);
      const RankRows given =
          rank_rows_pattern(part->mesh(), p.layout, p.global_row, p.first_row, p.last_row, share.owned, &coupled);
      require_same_owned_rows(given, walked);
      REQUIRE(given.halo_start == walked.halo_start);
      REQUIRE(given.halo_cols == walked.halo_cols);
      REQUIRE(given.owned.values.size() == walked.owned.values.size());
    });
}

// Under PETSc each process sums the errors of its own cells (the halo's belong to the process
// below) from its part's operator where the matrix came from it: against the cell-by-cell
// errors of the same cells, with the rounding bound of "Matrix-free error norms equal the
// cell-by-cell ones" (coefficients of order one, n elements along the longer side, area at
// most 3).
TEST_CASE("A part's operator gives the errors of its own cells", "[tensor_operator][solver]") {
  for (const char* file : {"/tests/mpi/tensor_affine_rows.toml", "/tests/mpi/tensor_mixed_conditions.toml"}) {
    INFO(file);
    const CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + file);
    const ExactSolution& exact = *c.problem.exact;
    std::map<int, int> with_halo;  // per number of processes (all but the first have a halo to leave out)
    for_each_part(c, [&](int ranks, int, const SplineSpace& part) {
      const CellRange owned = part.part()->owned;
      with_halo[ranks] += owned.last - owned.first < part.mesh().num_cells();
      const std::unique_ptr<MatrixFreePoisson> op = part.matrix_free_operator(1.0, 0.0, c.quadrature);
      REQUIRE(op);
      const Eigen::VectorXd coefficients = Eigen::VectorXd::Random(op->num_functions());
      std::array<double, 2> squares{};
      Eigen::VectorXd per_cell, expected_cells;
      REQUIRE(op->squared_errors(coefficients, exact, c.quadrature.error_points_u, c.quadrature.error_points_v, squares,
                                 &per_cell, owned));
      const std::array<double, 2> expected =
          squared_errors(part.mesh(), part.geometry(), coefficients, exact, c.quadrature, owned, &expected_cells);
      // n: the most elements along a side of the whole patch (its first row's cells, and the rows).
      int n_u = 0;
      while (n_u < part.mesh().num_cells() && part.mesh().cell(n_u).index_v == part.mesh().cell(0).index_v) ++n_u;
      const int n = std::max(n_u, part.part()->global_cells / n_u);
      const int p = std::max(part.degree()[0], part.degree()[1]);
      const double value = 64 * 2.2e-16 * (p + 1) * (p + 1) * coefficients.lpNorm<Eigen::Infinity>();
      const double l2_bound = value * std::sqrt(3.0), h1_bound = value * (1 + 2 * p * n) * std::sqrt(3.0);
      REQUIRE(std::abs(std::sqrt(squares[0]) - std::sqrt(expected[0])) <= l2_bound);
      REQUIRE(std::abs(std::sqrt(squares[1]) - std::sqrt(expected[1])) <= h1_bound);
      REQUIRE(per_cell.size() == part.mesh().num_cells());
      for (Eigen::Index k = 0; k < per_cell.size(); ++k) {
        const bool own = k >= owned.first && k < owned.last;
        INFO("cell " << k << (own ? " (owned)" : " (halo)") << ": " << per_cell[k] << " against " << expected_cells[k]);
        if (own) REQUIRE(std::abs(std::sqrt(per_cell[k]) - std::sqrt(expected_cells[k])) <= h1_bound);
        else REQUIRE(per_cell[k] == 0.0);
      }
    });
    REQUIRE(with_halo == std::map<int, int>{{2, 1}, {3, 2}});
  }
}

// Several patches glued C0 (the multipatch tensor space's operator, solver/glued_operator):
// its matrix, written patch by patch and added into the shared pattern, against the element
// loop over the glued mesh (the Dirichlet functions left out); its products and diagonal
// against that matrix, all functions free; its load against the element loop's. On the plus
// (B-splines, affine patches: Kronecker forms), the ring and the plate with a hole (NURBS:
// sum factorization).
TEST_CASE("Glued patches: the operator's matrix, products and load are the element loop's", "[tensor_operator][multipatch]") {
  for (const char* name : {"multipatch_plus", "multipatch_ring", "multipatch_plate_with_hole"})
    for (const int p : {2, 3}) {
      CaseDescription c = load_case(std::string(KNOTWORK_SOURCE_DIR) + "/cases/" + name + ".toml");
      patch_space(c).degree = {p, p};
      patch_space(c).elements_per_span = {3, 3};  // (patches meet in either direction)
      const std::unique_ptr<SplineSpace> space = build_space(c);
      const BezierMesh& mesh = space->mesh();
      const int n = mesh.num_functions();
      const double reaction = 0.7;
      const std::unique_ptr<MatrixFreePoisson> op = space->matrix_free_operator(1.0, reaction, c.quadrature);
      REQUIRE(op);
      REQUIRE(op->num_functions() == n);
      REQUIRE(op->assembles_lower());
      INFO(name << ", p = " << p);
      std::vector<bool> fixed;
      const Eigen::VectorXd g = project_dirichlet_data(mesh, space->geometry(), c.problem, c.quadrature, fixed);
      for (const bool all_free : {false, true}) {
        const DofLayout layout = make_dof_layout(n, all_free ? std::vector<bool>(n, false) : fixed);
        Eigen::SparseMatrix<double> A = lower_pattern_matrix(mesh, layout);
        PoissonForm form;
        form.reaction = reaction;
        form.source = &c.problem.source;
        Eigen::VectorXd F;
        assemble_poisson(mesh, space->geometry(), form, layout, Eigen::VectorXd::Zero(n), c.quadrature, A, F);
        const Eigen::SparseMatrix<double> B = op->lower_matrix(layout);
        REQUIRE(A.nonZeros() == B.nonZeros());
        REQUIRE(std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1, B.outerIndexPtr()));
        REQUIRE(std::equal(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros(), B.innerIndexPtr()));
        // The pattern alone (what the element loop fills where the operator cannot write the
        // matrix: Nitsche's terms, variable coefficients), zeros.
        REQUIRE(op->gives_pattern());
        const Eigen::SparseMatrix<double> P = op->lower_pattern(layout);
        REQUIRE(std::equal(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1, P.outerIndexPtr()));
        REQUIRE(std::equal(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros(), P.innerIndexPtr()));
        REQUIRE(Eigen::Map<const Eigen::VectorXd>(P.valuePtr(), P.nonZeros()).isZero(0));
        // As for one patch, each entry a sum of at most 2 patches' positive semi-definite
        // integrands (3 or 4 at a vertex), bounded by sqrt(K_aa K_bb).
        const double m = 4 * 8.0 * std::pow(p + 1, 4) * 2.2e-16;
        for (int k = 0; k < A.outerSize(); ++k)
          for (Eigen::SparseMatrix<double>::InnerIterator a(A, k), b(B, k); a; ++a, ++b)
            REQUIRE(std::abs(a.value() - b.value()) <= m * std::sqrt(A.coeff(a.row(), a.row()) * A.coeff(k, k)));
        if (!all_free) continue;
        // All functions free: dofs are functions. K x and the diagonal against A's.
        const Eigen::SparseMatrix<double> whole = A.selfadjointView<Eigen::Lower>();
        const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(n, -1, 2).array().sin();
        Eigen::VectorXd y;
        op->apply(x, y);
        const double scale = inf_norm(A) * x.lpNorm<Eigen::Infinity>();
        REQUIRE((y - whole * x).lpNorm<Eigen::Infinity>() <= m * (2 * p + 1) * (2 * p + 1) * scale);
        REQUIRE((op->diagonal() - A.diagonal()).lpNorm<Eigen::Infinity>() <= m * A.diagonal().maxCoeff());
        // The load, f R_a by the same rules: a sum of terms bounded by |f|_inf |R_a|_L1.
        const Eigen::VectorXd load = op->load(c.problem.source);
        REQUIRE((load - F).lpNorm<Eigen::Infinity>() <= m * (2 * p + 1) * (2 * p + 1) * F.lpNorm<Eigen::Infinity>() + 1e-300);
      }
    }
}
