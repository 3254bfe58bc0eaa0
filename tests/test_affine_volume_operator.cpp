// The operator of a trivariate B-spline space on one affine map (solver/affine_volume_operator),
// checked against the element loop (solver/assemble_poisson: Bezier extraction, the map evaluated
// at every Gauss point, J inverted there), an independent computation of the same integrals:
// - affine_map finds one affine map, and refuses a curved map, a trilinear non-parallelepiped and
//   unequal weights;
// - the matrix over the free dofs has the element loop's pattern and, entry by entry, its values
//   within the rounding bound below, on a sheared parallelepiped with unequal degrees, non-uniform
//   knots, a C0 knot and a reaction term;
// - the load, the diagonal and the product K x agree with the element loop's load and matrix;
// - a source that is not finite is refused with the element loop's words;
// - its error norms (sums one direction at a time, no mesh) are the mesh's error_norms';
// - knotwork run on the cube writes the matrix this way, and on the curved annulus does not.
//
// The bound: both sides sum the same products of basis values, weights and the metric in other
// orders, so an entry differs by at most a few times m eps sum |terms|, m the number of summands
// (at most 8 cells x 64 points here, and the terms of the metric). For the stiffness,
// |grad phi_i . G grad phi_j| <= (grad phi_i . G grad phi_i + grad phi_j . G grad phi_j) / 2 at every
// point (G positive definite), so sum |terms| <= (K_ii + K_jj) / 2; the element loop's G comes from
// J inverted at each point, off by about cond(J) eps.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "cli_sandbox.hpp"
#include "solver/affine_volume_operator.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/error_norms.hpp"
#include "solver/expression.hpp"
#include "solver/sparsity.hpp"

using namespace knotwork;

namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();

Eigen::Matrix3d shear() {
  Eigen::Matrix3d J;
  J << 2.0, 0.3, 0.1, 0.2, 1.5, -0.4, 0.1, 0.2, 0.8;
  return J;
}

// The map x = origin + J (u, v, w) as a volume of degrees (2, 1, 1) with a non-uniform knot in u:
// its control points are the map at the Greville abscissae (linear precision).
NurbsVolume affine_volume(const Eigen::Vector3d& origin, const Eigen::Matrix3d& J) {
  NurbsVolume volume;
  volume.bases = {BSplineBasis1D(2, {0, 0, 0, 0.3, 1, 1, 1}), BSplineBasis1D(1, {0, 0, 1, 1}), BSplineBasis1D(1, {0, 0, 1, 1})};
  const std::vector<double> gu = greville_abscissae(volume.bases[0]);
  const int nu = static_cast<int>(gu.size());
  volume.control_points.resize(nu * 4, 3);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < nu; ++i)
        volume.control_points.row(i + nu * (j + 2 * k)) = (origin + J * Eigen::Vector3d(gu[i], j, k)).transpose();
  volume.weights.setConstant(nu * 4, 1.0);
  return volume;
}

// The space: degree 2 in u with a C0 knot, 3 in v, 1 in w, non-uniform knots.
std::array<BSplineBasis1D, 3> test_space() {
  return {BSplineBasis1D(2, {0, 0, 0, 0.3, 0.5, 0.5, 1, 1, 1}), BSplineBasis1D(3, {0, 0, 0, 0, 0.6, 1, 1, 1, 1}),
          BSplineBasis1D(1, {0, 0, 0.2, 0.45, 0.7, 1, 1})};
}

struct Setup {
  std::array<BSplineBasis1D, 3> space = test_space();
  BezierMesh mesh;
  NurbsVolume volume = affine_volume(Eigen::Vector3d(0.5, -1, 2), shear());
  std::vector<bool> fixed;
  DofLayout layout;
  int n[3];
  Setup() {
    add_tensor_cells(mesh, space, 0, space[2].num_elements());
    for (int d = 0; d < 3; ++d) n[d] = space[d].num_functions();
    const int functions = n[0] * n[1] * n[2];
    mesh.set_num_functions(functions);
    fixed.assign(functions, false);
    // The functions on the faces u = 0, v = 1 and w = 1 fixed: a layout with holes.
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) fixed[i + n[0] * (j + n[1] * k)] = i == 0 || j == n[1] - 1 || k == n[2] - 1;
    layout = make_dof_layout(functions, fixed);
  }
};

// The element loop's lower matrix and load over `layout` (Dirichlet values zero).
void element_loop(const Setup& s, const Expression& source, double stiffness, double reaction,
                  Eigen::SparseMatrix<double>& K, Eigen::VectorXd& load) {
  const VolumeGeometryMap map(s.mesh, s.volume);
  PoissonForm form;
  form.stiffness = stiffness;
  form.reaction = reaction;
  form.source = &source;
  K = lower_pattern_matrix(s.mesh, s.layout);
  assemble_poisson(s.mesh, map, form, s.layout, Eigen::VectorXd::Zero(s.mesh.num_functions()), QuadratureOptions{}, K, load);
}

}  // namespace

TEST_CASE("affine_map finds one affine map, and only that", "[affine_volume]") {
  const Eigen::Vector3d origin(0.5, -1, 2);
  const std::optional<AffineVolumeMap> m = affine_map(affine_volume(origin, shear()));
  REQUIRE(m);
  CHECK((m->jacobian - shear()).cwiseAbs().maxCoeff() <= 16 * eps * shear().cwiseAbs().maxCoeff());
  CHECK((m->origin - origin).cwiseAbs().maxCoeff() <= 16 * eps * 4);

  NurbsVolume moved = affine_volume(origin, shear());  // one corner moved: trilinear, not affine
  moved.control_points(moved.control_points.rows() - 1, 2) += 1e-3;
  CHECK_FALSE(affine_map(moved));
  NurbsVolume middle = affine_volume(origin, shear());  // an inner control point of the quadratic moved
  middle.control_points(1, 0) += 1e-3;
  CHECK_FALSE(affine_map(middle));
  NurbsVolume weighted = affine_volume(origin, shear());  // unequal weights: a rational map
  weighted.weights[1] = 0.9;
  CHECK_FALSE(affine_map(weighted));
}

TEST_CASE("The Kronecker-form matrix is the element loop's, entry by entry", "[affine_volume]") {
  const Setup s;
  const Expression source = Expression::parse("1", "test");
  for (const auto& [stiffness, reaction] : {std::pair{1.0, 0.0}, std::pair{1.3, 0.7}}) {
    Eigen::SparseMatrix<double> loop;
    Eigen::VectorXd unused;
    element_loop(s, source, stiffness, reaction, loop, unused);
    const AffineVolumeOperator op(s.space, *affine_map(s.volume), stiffness, reaction);
    const Eigen::SparseMatrix<double> written = op.lower_matrix(s.layout);
    REQUIRE(written.nonZeros() == loop.nonZeros());
    REQUIRE(std::equal(written.outerIndexPtr(), written.outerIndexPtr() + written.cols() + 1, loop.outerIndexPtr()));
    REQUIRE(std::equal(written.innerIndexPtr(), written.innerIndexPtr() + written.nonZeros(), loop.innerIndexPtr()));
    const Eigen::VectorXd diagonal = Eigen::VectorXd(loop.diagonal());
    const Eigen::Vector3d lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(shear().transpose() * shear()).eigenvalues();
    const double condition = std::sqrt(lambda[2] / lambda[0]);  // of J
    const double m = 8 * 64 + 20;  // summands per entry: cells x points, and the metric's terms
    double worst = 0;
    for (int c = 0; c < loop.outerSize(); ++c)
      for (Eigen::SparseMatrix<double>::InnerIterator it(loop, c); it; ++it) {
        const double bound = 4 * (m + 10 * condition) * eps * (diagonal[it.row()] + diagonal[c]) / 2;
        const double difference = std::abs(written.coeff(it.row(), c) - it.value());
        worst = std::max(worst, difference / bound);
      }
    INFO("stiffness " << stiffness << ", reaction " << reaction << ": worst difference / bound " << worst);
    CHECK(worst <= 1);
    // Not vacuous: the matrix has mixed-metric entries of both signs.
    CHECK(loop.coeffs().minCoeff() < 0);
  }
}

TEST_CASE("The operator's load, diagonal and product agree with the assembled ones", "[affine_volume]") {
  const Setup s;
  // A positive source: every term of F_a is positive, so sum |terms| = F_a.
  const Expression source = Expression::parse("2 + sin(x)*cos(y)*z/10", "test");
  Eigen::SparseMatrix<double> loop;
  Eigen::VectorXd loop_load;
  element_loop(s, source, 1.0, 0.5, loop, loop_load);
  const AffineVolumeOperator op(s.space, *affine_map(s.volume), 1.0, 0.5);
  const Eigen::VectorXd load = op.load(source);
  const double m = 8 * 64 + 20;
  for (int d = 0; d < s.layout.num_free(); ++d) {
    const int f = s.layout.function_of_dof[d];
    REQUIRE(loop_load[d] > 0);
    CHECK(std::abs(load[f] - loop_load[d]) <= 4 * m * eps * loop_load[d]);
  }
  // Over all functions (nothing fixed) the operator's K, its diagonal and K x.
  const int functions = s.mesh.num_functions();
  const DofLayout all = make_dof_layout(functions, std::vector<bool>(functions, false));
  const Eigen::SparseMatrix<double> lower = op.lower_matrix(all);
  const Eigen::SparseMatrix<double> K = Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>());
  CHECK((op.diagonal() - Eigen::VectorXd(K.diagonal())).cwiseAbs().maxCoeff() == 0);  // the same sums
  Eigen::VectorXd x(functions);
  for (int f = 0; f < functions; ++f) x[f] = std::sin(0.37 * f + 0.1);
  Eigen::VectorXd y;
  op.apply(x, y);
  const Eigen::VectorXd expected = K * x;
  // Each y_i sums the same products in another order: within m eps sum_j |K_ij| |x_j|, m the
  // terms of an entry (10) times the couplings of a row.
  const Eigen::VectorXd size = Eigen::SparseMatrix<double>(K.cwiseAbs()) * x.cwiseAbs();
  const double couplings = op.max_row_nonzeros();
  for (int f = 0; f < functions; ++f) CHECK(std::abs(y[f] - expected[f]) <= 4 * 10 * couplings * eps * size[f]);
  // The rows a distributed solve writes: row_entries gives K's entries, coupled_functions its pattern.
  std::vector<int> columns;
  op.coupled_functions(17, columns);
  std::vector<double> values(columns.size());
  op.row_entries(17, static_cast<int>(columns.size()), columns.data(), values.data());
  int stored = 0;
  for (Eigen::SparseMatrix<double>::InnerIterator it(Eigen::SparseMatrix<double>(K.transpose()), 17); it; ++it) ++stored;
  CHECK(static_cast<int>(columns.size()) == stored);
  for (size_t k = 0; k < columns.size(); ++k) CHECK(values[k] == K.coeff(17, columns[k]));
}

TEST_CASE("A source that is not finite is refused in the element loop's words", "[affine_volume]") {
  const Setup s;
  const Expression source = Expression::parse("sqrt(2-x)", "case.toml: [problem] source");
  std::string loop_message, operator_message;
  try {
    Eigen::SparseMatrix<double> K;
    Eigen::VectorXd load;
    element_loop(s, source, 1.0, 0.0, K, load);
  } catch (const InputError& e) {
    loop_message = e.what();
  }
  try {
    AffineVolumeOperator(s.space, *affine_map(s.volume), 1.0, 0.0).load(source);
  } catch (const InputError& e) {
    operator_message = e.what();
  }
  INFO(loop_message);
  REQUIRE(!loop_message.empty());
  CHECK(operator_message == loop_message);
}

TEST_CASE("knotwork run writes the cube's matrix from the Kronecker form, not the annulus's", "[affine_volume]") {
  const cli_test::Sandbox box;
  const std::string cases = std::string(KNOTWORK_SOURCE_DIR) + "/cases/";
  const cli_test::Result cube = box.run("run " + cases + "cube.toml --elements 8 --json -q --no-output");
  INFO(cube.err);
  REQUIRE(cube.code == 0);
  CHECK(cube.out.find("\"assembly_method\": \"kronecker_form\"") != std::string::npos);
  const cli_test::Result annulus = box.run("run " + cases + "thick_quarter_annulus.toml --elements 2 --json -q --no-output");
  INFO(annulus.err);
  REQUIRE(annulus.code == 0);
  CHECK(annulus.out.find("\"assembly_method\": \"element_loop\"") != std::string::npos);
}

namespace {

double json_number(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\": ");
  REQUIRE(at != std::string::npos);
  return std::stod(text.substr(at + key.size() + 4));
}

}  // namespace

TEST_CASE("Rows of a box of functions by mode products: the matrix's rows", "[affine_volume]") {
  // The Setup's free functions (all but the faces u = 0, v = 1, w = 1) are a box; its layout
  // numbers them as the box does. K x over the whole box and over a block inside it, against
  // the matrix the operator writes entry by entry (entry(): products of band entries), within
  // the bound of the product test above.
  const Setup s;
  const AffineVolumeOperator op(s.space, *affine_map(s.volume), 1.0, 0.5);
  const AffineVolumeOperator::FunctionBox free{{1, 0, 0}, {s.n[0] - 1, s.n[1] - 1, s.n[2] - 1}};
  REQUIRE(free.size() == s.layout.num_free());
  const Eigen::SparseMatrix<double> lower = op.lower_matrix(s.layout);
  const Eigen::SparseMatrix<double> K = Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>());
  Eigen::VectorXd x(free.size());
  for (long d = 0; d < x.size(); ++d) x[d] = std::cos(0.53 * d + 0.2);
  const Eigen::VectorXd expected = K * x;
  const Eigen::VectorXd size = Eigen::SparseMatrix<double>(K.cwiseAbs()) * x.cwiseAbs();
  const double bound = 4 * 10 * op.max_row_nonzeros() * eps;
  Eigen::VectorXd y(free.size());
  op.apply_within(x.data(), free, y.data());
  for (long d = 0; d < y.size(); ++d) CHECK(std::abs(y[d] - expected[d]) <= bound * size[d]);
  // A block touching the box's last face in v (rows whose reach is cut there) and inside in u, w.
  const AffineVolumeOperator::FunctionBox rows{{2, free.count[1] - 3, 1}, {3, 3, 2}};
  Eigen::VectorXd block(rows.size());
  op.apply_box(x.data(), free, rows, block.data());
  long at = 0;
  for (int k = 0; k < rows.count[2]; ++k)
    for (int j = 0; j < rows.count[1]; ++j)
      for (int i = 0; i < rows.count[0]; ++i, ++at) {
        const long d = (rows.first[0] - free.first[0] + i) +
                       long(free.count[0]) * ((rows.first[1] - free.first[1] + j) + long(free.count[1]) * (rows.first[2] - free.first[2] + k));
        CHECK(std::abs(block[at] - expected[d]) <= bound * size[d]);
      }
}

TEST_CASE("CG without a matrix on the cube: the assembled solve's errors, and a clear refusal on a curved volume",
          "[affine_volume]") {
  const cli_test::Sandbox box;
  const std::string cube = std::string(KNOTWORK_SOURCE_DIR) + "/cases/cube.toml --elements 24 --json -q --no-output";
  const cli_test::Result free = box.run("run " + cube);  // "auto": CG without a matrix on an affine volume (26^3 functions)
  INFO(free.err);
  REQUIRE(free.code == 0);
  CHECK(free.out.find("\"assembly_method\": \"none\"") != std::string::npos);
  CHECK(free.out.find("\"matrix\": \"matrix_free\"") != std::string::npos);
  const cli_test::Result direct = box.run("run " + cube + " --solver direct --condition");
  REQUIRE(direct.code == 0);
  // Both solve K c = F (K's entries equal to rounding: the test cases above): CG to a backward
  // error of 1e-15, CHOLMOD backward stably. The coefficients then differ by about
  // kappa (1e-15 + eps) relative, kappa the Jacobi-scaled condition number; the L2 error by at
  // most that times |u_h|_L2 <= 1 (u = sin sin sin: 0.35), the H1-seminorm error times
  // |u_h|_H1 (2 here) times sqrt(kappa) for the scaling between the norms.
  const double kappa = json_number(direct.out, "stiffness");
  REQUIRE(kappa > 1);
  const double relative = 10 * kappa * (1e-15 + eps);
  CHECK(std::abs(json_number(free.out, "l2_error") - json_number(direct.out, "l2_error")) <= relative);
  CHECK(std::abs(json_number(free.out, "h1_seminorm_error") - json_number(direct.out, "h1_seminorm_error")) <=
        2 * std::sqrt(kappa) * relative);
  // Asked for on a curved volume, the refusal names why.
  const cli_test::Result curved = box.run("run " + std::string(KNOTWORK_SOURCE_DIR) +
                                          "/cases/thick_quarter_annulus.toml --elements 2 --solver iterative --matrix matrix_free -q --no-output");
  CHECK(curved.code != 0);
  CHECK(curved.err.find("[solver] matrix: \"matrix_free\" is not available here (NURBS functions are not products of "
                        "univariate ones); use \"assembled\" or \"auto\"") != std::string::npos);
}

TEST_CASE("The operator's error norms are the mesh's, without the mesh", "[affine_volume]") {
  const Setup s;
  const VolumeGeometryMap map(s.mesh, s.volume);
  const AffineVolumeOperator op(s.space, *affine_map(s.volume), 1.0, 0.0);
  const int functions = s.mesh.num_functions();
  const QuadratureOptions rule;  // degree + 2 points per direction, on both sides
  // (1) Coefficients far from u: every term of the sums is a square of size 1, summed in
  // another order (and u_h, grad u_h formed in another order): within m eps of the totals,
  // m the terms (8 cells x 125 points here, times the few products of a term).
  const ExactSolution smooth = differentiate_volume_solution(Expression::parse("sin(x)*cos(y)*z", "test"));
  Eigen::VectorXd c(functions);
  for (int f = 0; f < functions; ++f) c[f] = std::cos(0.7 * f);
  std::array<double, 2> by_operator{};
  Eigen::VectorXd per_cell;
  REQUIRE(op.squared_errors(c, smooth, 0, 0, by_operator, &per_cell));
  Eigen::VectorXd mesh_per_cell;
  const std::array<double, 2> by_mesh = squared_errors(s.mesh, map, c, smooth, rule, CellRange{}, &mesh_per_cell);
  const double m = 8 * 125 * 20;
  CHECK(by_mesh[0] > 0.01);
  CHECK(std::abs(by_operator[0] - by_mesh[0]) <= m * eps * by_mesh[0]);
  CHECK(std::abs(by_operator[1] - by_mesh[1]) <= m * eps * by_mesh[1]);
  REQUIRE(per_cell.size() == s.mesh.num_cells());
  for (int cell = 0; cell < s.mesh.num_cells(); ++cell)
    CHECK(std::abs(per_cell[cell] - mesh_per_cell[cell]) <= m * eps * mesh_per_cell[cell]);
  // Over a range of cells only (a process's own), 0 elsewhere.
  std::array<double, 2> part{};
  REQUIRE(op.squared_errors(c, smooth, 0, 0, part, &per_cell, CellRange{3, 9}));
  double expected = 0;
  for (int cell = 3; cell < 9; ++cell) expected += mesh_per_cell[cell];
  CHECK(std::abs(part[1] - expected) <= m * eps * expected);
  CHECK(per_cell[2] == 0);
  // A rule of more than 16 points, as [space] error_quadrature_points allows (up to 30): the
  // same sums (this once was refused).
  const AffineVolumeOperator fine(s.space, *affine_map(s.volume), 1.0, 0.0, {0, 0, 0}, 20);
  QuadratureOptions rule20;
  rule20.error_points_u = rule20.error_points_v = rule20.error_points_w = 20;
  REQUIRE(fine.squared_errors(c, smooth, 20, 20, by_operator, nullptr));
  const std::array<double, 2> by_mesh20 = squared_errors(s.mesh, map, c, smooth, rule20, CellRange{});
  const double m20 = 8 * 8000 * 20;
  CHECK(std::abs(by_operator[0] - by_mesh20[0]) <= m20 * eps * by_mesh20[0]);
  CHECK(std::abs(by_operator[1] - by_mesh20[1]) <= m20 * eps * by_mesh20[1]);
  // (2) u linear, in the space: its coefficients are its values at the Greville points (linear
  // precision, the map being affine), so both errors are rounding, below c eps |u| (c: the
  // terms of u_h at a point, 3^3 products of a few factors each).
  const ExactSolution linear = differentiate_volume_solution(Expression::parse("2*x - y + 3*z + 1", "test"));
  const std::vector<double> gu = greville_abscissae(s.space[0]), gv = greville_abscissae(s.space[1]), gw = greville_abscissae(s.space[2]);
  const AffineVolumeMap affine = *affine_map(s.volume);
  for (int k = 0; k < s.n[2]; ++k)
    for (int j = 0; j < s.n[1]; ++j)
      for (int i = 0; i < s.n[0]; ++i) {
        const Eigen::Vector3d x = affine.origin + affine.jacobian * Eigen::Vector3d(gu[i], gv[j], gw[k]);
        c[i + s.n[0] * (j + s.n[1] * k)] = 2 * x[0] - x[1] + 3 * x[2] + 1;
      }
  REQUIRE(op.squared_errors(c, linear, 0, 0, by_operator, nullptr));
  const std::array<double, 2> size = squared_errors(s.mesh, map, Eigen::VectorXd::Zero(functions), linear, rule, CellRange{});
  INFO("L2 " << std::sqrt(by_operator[0]) << " of |u| " << std::sqrt(size[0]));
  CHECK(std::sqrt(by_operator[0]) <= 1e3 * eps * std::sqrt(size[0]));
  CHECK(std::sqrt(by_operator[1]) <= 1e3 * eps * std::sqrt(size[1]));
}
