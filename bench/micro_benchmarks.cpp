// Micro-benchmarks of the kernels the solver spends its time in. Run:
//   build/bench/knotwork_micro_bench --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include "studies/pipeline.hpp"
#include "cases/case_file.hpp"
#include "cases/geometries.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/error_norms.hpp"
#include "solver/sparsity.hpp"
#include "solver/tensor_operator.hpp"

using namespace knotwork;

namespace {

CaseDescription square(int p, int n) { return unit_square_benchmark_case(p, n); }

void BM_BezierExtraction(benchmark::State& state) {
  const auto b = BSplineBasis1D::open_uniform(static_cast<int>(state.range(0)), 0, 1, 1024);
  for (auto _ : state) benchmark::DoNotOptimize(bezier_extraction(b));
  state.SetItemsProcessed(state.iterations() * 1024);
}
BENCHMARK(BM_BezierExtraction)->Arg(2)->Arg(4);

// The benchmark square's space, its Dirichlet values and free dofs, and the form with its source.
struct SquareProblem {
  CaseDescription c;
  std::unique_ptr<SplineSpace> space;
  Eigen::VectorXd g;
  DofLayout layout;
  PoissonForm form;
  explicit SquareProblem(const benchmark::State& state)
      : c(square(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)))), space(build_space(c)) {
    std::vector<bool> fixed;
    g = project_dirichlet_data(space->mesh(), space->geometry(), c.problem, c.quadrature, fixed);
    layout = make_dof_layout(space->mesh().num_functions(), fixed);
    form.source = &c.problem.source;
  }
};

void BM_AssemblePoisson(benchmark::State& state) {
  const SquareProblem s(state);
  const SplineSpace& d = *s.space;
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(d.mesh(), s.layout);
  Eigen::VectorXd rhs;
  for (auto _ : state) assemble_poisson(d.mesh(), d.geometry(), s.form, s.layout, s.g, s.c.quadrature, K, rhs);
  state.SetItemsProcessed(state.iterations() * d.mesh().num_cells());
  state.counters["cells"] = d.mesh().num_cells();
}
BENCHMARK(BM_AssemblePoisson)->Args({2, 128})->Args({4, 64})->Args({2, 512})->Args({4, 256})->Unit(benchmark::kMillisecond);

// The same matrix (lower triangle over the free dofs, pattern included) written from the
// operator's Kronecker form (solver/tensor_operator_matrix.cpp): compare with BM_AssemblePoisson
// plus BM_LowerPattern on the same sizes (the load is not included here).
void BM_KroneckerMatrix(benchmark::State& state) {
  const SquareProblem s(state);
  const std::unique_ptr<MatrixFreePoisson> op = s.space->matrix_free_operator(1.0, 0.0, s.c.quadrature);
  if (!op || !op->assembles_lower()) {
    state.SkipWithError("the square's operator does not write its matrix");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(op->lower_matrix(s.layout));
  state.SetItemsProcessed(state.iterations() * s.space->mesh().num_cells());
}
BENCHMARK(BM_KroneckerMatrix)->Args({2, 128})->Args({4, 64})->Args({2, 512})->Args({4, 256})->Unit(benchmark::kMillisecond);

// A curved patch's matrix (the quarter annulus, lower triangle over the free dofs, pattern
// included, no load): the element loop (path 0: lower_pattern_matrix and assemble_poisson)
// against the operator's sum factorization (path 1: solver/tensor_operator_sum_factorized.cpp),
// on the NURBS space (rational 1) or on B-splines over the same exact map (rational 0).
void BM_CurvedMatrix(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  const std::string text = "[geometry]\ntype = \"quarter_annulus\"\n[space]\ndegree = " + std::to_string(p) +
                           "\nelements = " + std::to_string(n) + "\nrational = " + (state.range(3) ? "true" : "false") +
                           "\n[problem]\nexact = \"-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2\"\n";
  const CaseDescription c = load_case_text(text, "bench");
  const std::unique_ptr<SplineSpace> space = build_space(c);
  std::vector<bool> fixed;
  const Eigen::VectorXd g = project_dirichlet_data(space->mesh(), space->geometry(), c.problem, c.quadrature, fixed);
  const DofLayout layout = make_dof_layout(space->mesh().num_functions(), fixed);
  if (state.range(2) == 0) {
    PoissonForm form;
    form.load = false;
    Eigen::VectorXd rhs;
    for (auto _ : state) {
      Eigen::SparseMatrix<double> K = lower_pattern_matrix(space->mesh(), layout);
      assemble_poisson(space->mesh(), space->geometry(), form, layout, g, c.quadrature, K, rhs);
      benchmark::DoNotOptimize(K.valuePtr());
    }
  } else {
    const std::unique_ptr<MatrixFreePoisson> op = space->matrix_free_operator(1.0, 0.0, c.quadrature);
    for (auto _ : state) benchmark::DoNotOptimize(op->lower_matrix(layout));
  }
  state.SetItemsProcessed(state.iterations() * space->mesh().num_functions());
}
BENCHMARK(BM_CurvedMatrix)
    ->ArgNames({"p", "n", "path", "rational"})
    ->ArgsProduct({{2}, {512}, {0, 1}, {0, 1}})
    ->ArgsProduct({{4}, {256}, {0, 1}, {0, 1}})
    ->ArgsProduct({{6}, {128}, {0, 1}, {1}})
    ->Unit(benchmark::kMillisecond);

// What the Kronecker form's path still integrates: the load, f at every quadrature point of the
// same square (the case's derived source, compiled), by the operator's sum factorization.
void BM_OperatorLoad(benchmark::State& state) {
  const SquareProblem s(state);
  const std::unique_ptr<MatrixFreePoisson> op = s.space->matrix_free_operator(1.0, 0.0, s.c.quadrature);
  for (auto _ : state) benchmark::DoNotOptimize(op->load(s.c.problem.source));
  state.SetItemsProcessed(state.iterations() * s.space->mesh().num_cells());
}
BENCHMARK(BM_OperatorLoad)->Args({2, 512})->Args({4, 256})->Unit(benchmark::kMillisecond);

// Rank 0 of 2 under mpirun, on one thread: its half of the cells, whole rows of its half of
// the functions (PETSc's blocks, rank_rows_pattern), against the serial kernel on the same
// cells (lower triangle), also on one thread. Run with OMP_NUM_THREADS=1 to compare kernels.
void BM_AssembleHalf(benchmark::State& state) {
  const SquareProblem s(state);
  const SplineSpace& d = *s.space;
  const int n = s.layout.num_free();
  const CellRange half{0, d.mesh().num_cells() / 2};
  Eigen::VectorXd rhs;
  if (state.range(2) == 1) {
    std::vector<int> rows(n);
    for (int k = 0; k < n; ++k) rows[k] = k;
    RankRows r = rank_rows_pattern(d.mesh(), s.layout, rows, 0, n / 2, half);
    for (auto _ : state) assemble_poisson(d.mesh(), d.geometry(), s.form, s.layout, s.g, s.c.quadrature, r, rhs, half);
  } else {
    Eigen::SparseMatrix<double> K = lower_pattern_matrix(d.mesh(), s.layout);
    for (auto _ : state)
      assemble_poisson(d.mesh(), d.geometry(), s.form, s.layout, s.g, s.c.quadrature, K, rhs, nullptr, half);
  }
  state.SetItemsProcessed(state.iterations() * half.last);
}
BENCHMARK(BM_AssembleHalf)->ArgNames({"p", "n", "rows"})->Args({2, 256, 0})->Args({2, 256, 1})->Args({4, 128, 0})->Args({4, 128, 1})->Unit(benchmark::kMillisecond);

void BM_ErrorNorms(benchmark::State& state) {
  const CaseDescription c = square(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const std::unique_ptr<SplineSpace> space = build_space(c);
  const SplineSpace& d = *space;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(d.mesh().num_functions());
  for (auto _ : state) benchmark::DoNotOptimize(error_norms(d.mesh(), d.geometry(), u, *c.problem.exact, c.quadrature));
  state.SetItemsProcessed(state.iterations() * d.mesh().num_cells());
}
BENCHMARK(BM_ErrorNorms)->Args({2, 128})->Args({4, 64})->Unit(benchmark::kMillisecond);

void BM_LowerPattern(benchmark::State& state) {
  const CaseDescription c = square(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const std::unique_ptr<SplineSpace> space = build_space(c);
  const SplineSpace& d = *space;
  const DofLayout layout = make_dof_layout(d.mesh().num_functions(), std::vector<bool>(d.mesh().num_functions(), false));
  for (auto _ : state) benchmark::DoNotOptimize(lower_pattern_matrix(d.mesh(), layout));
}
BENCHMARK(BM_LowerPattern)->Args({2, 128})->Args({4, 64})->Args({2, 512})->Args({4, 256})->Args({2, 1024})->Args({4, 512})->Unit(benchmark::kMillisecond);

// CG's product with the stiffness matrix stored as its lower triangle (Eigen's selfadjointView).
void BM_SymmetricProduct(benchmark::State& state) {
  const CaseDescription c = square(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const std::unique_ptr<SplineSpace> space = build_space(c);
  const SplineSpace& d = *space;
  const DofLayout layout = make_dof_layout(d.mesh().num_functions(), std::vector<bool>(d.mesh().num_functions(), false));
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(d.mesh(), layout);
  Eigen::VectorXd rhs;
  PoissonForm form;
  form.source = &c.problem.source;
  assemble_poisson(d.mesh(), d.geometry(), form, layout, Eigen::VectorXd::Zero(layout.num_free()), c.quadrature, K, rhs);
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(K.rows(), 0, 1);
  Eigen::VectorXd y(K.rows());
  for (auto _ : state) {
    y.noalias() = K.selfadjointView<Eigen::Lower>() * x;
    benchmark::DoNotOptimize(y.data());
  }
  state.SetItemsProcessed(state.iterations() * K.nonZeros());
}
BENCHMARK(BM_SymmetricProduct)->Args({2, 512})->Args({4, 256})->Unit(benchmark::kMillisecond);

// The same product without a matrix: sum factorization element by element, the geometry
// evaluated from its control net at every application (solver/tensor_operator), over all
// functions of the same square. Compare with BM_SymmetricProduct at the same arguments.
// The square is the identity map written in the space itself: control points at the
// Greville abscissae (B-splines reproduce linear functions), weights 1.
void BM_TensorOperatorApply(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0)), n = static_cast<int>(state.range(1));
  const BSplineBasis1D b = BSplineBasis1D::open_uniform(p, 0, 1, n);
  const int m = b.num_functions();
  const std::vector<double> xi = greville_abscissae(b);
  Eigen::MatrixX3d net(long(m) * m, 3);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) net.row(i + long(m) * j) << xi[i], xi[j], 1.0;
  const Eigen::VectorXd weights;
  const TensorPoissonOperator A({&b, &b, &weights, &b, &b, &net}, 1.0, 0.0);
  const Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(A.num_functions(), 0, 1);
  Eigen::VectorXd y(A.num_functions());
  for (auto _ : state) {
    A.apply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  state.SetItemsProcessed(state.iterations() * A.num_functions());
}
BENCHMARK(BM_TensorOperatorApply)->Args({2, 512})->Args({4, 256})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
