// Trivariate tensor-product B-splines as hexahedral cells of a BezierMesh (add_tensor_cells in
// three directions), checked by properties that do not depend on the construction: counts from
// the knot vectors, partition of unity, linear independence, values against products of
// univariate B-splines evaluated by de Boor's recurrence, and Marsden's identity. Then a NURBS
// volume as their geometry and the cell basis on hexahedra: a polynomial map's exact volume, and
// the isoparametric identity (coefficients = control points reproduce x, y, z and their
// gradients) on a thick quarter annulus. Last, Poisson's problem on the unit cube through the
// one assembler, against an exact solution: the errors fall at the rates theory gives, with the
// boundary functions fixed at 0 or by the L2 projection of the exact solution on the faces; and
// the patch test (a trilinear u reproduced to rounding).
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "basis/core/bezier_mesh_checks.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/tensor/tensor_patch.hpp"
#include "solver/affine_volume_operator.hpp"
#include "solver/assemble_poisson.hpp"
#include "solver/cell_basis.hpp"
#include "solver/error_norms.hpp"
#include "solver/poisson_problem.hpp"
#include "solver/poisson_solver.hpp"
#include "solver/expression.hpp"
#include "solver/sparsity.hpp"
#include "rounding_bounds.hpp"

using namespace knotwork;

namespace {

constexpr double eps = std::numeric_limits<double>::epsilon();

// Degree p on [0, 1] with `elements` equal elements and C^r at the interior knots.
BSplineBasis1D uniform_basis(int p, int elements, int r) {
  std::vector<double> knots(p + 1, 0.0);
  for (int e = 1; e < elements; ++e) knots.insert(knots.end(), p - r, double(e) / elements);
  knots.insert(knots.end(), p + 1, 1.0);
  return BSplineBasis1D(p, knots);
}

// The number of such functions, from the construction (p + 1 at the first element, p - r
// more at each interior knot).
int expected_functions(int p, int elements, int r) { return p + 1 + (elements - 1) * (p - r); }

struct Volume {
  std::array<BSplineBasis1D, 3> bases;
  std::array<int, 3> p, elements, r;
  BezierMesh mesh;
};

Volume make_volume(std::array<int, 3> p, std::array<int, 3> elements, std::array<int, 3> r) {
  Volume v{{uniform_basis(p[0], elements[0], r[0]), uniform_basis(p[1], elements[1], r[1]),
            uniform_basis(p[2], elements[2], r[2])},
           p, elements, r, BezierMesh()};
  add_tensor_cells(v.mesh, v.bases, 0, elements[2]);
  v.mesh.set_num_functions(expected_functions(p[0], elements[0], r[0]) * expected_functions(p[1], elements[1], r[1]) *
                           expected_functions(p[2], elements[2], r[2]));
  return v;
}

// The p + 1 Bernstein polynomials of degree p at t, by their definition.
std::vector<double> bernstein(int p, double t) {
  std::vector<double> b(p + 1);
  for (int a = 0; a <= p; ++a) b[a] = std::tgamma(p + 1.0) / (std::tgamma(a + 1.0) * std::tgamma(p - a + 1.0)) *
                                      std::pow(t, a) * std::pow(1 - t, p - a);
  return b;
}

// The cell holding the point, and the values there of the functions alive on it through the
// cell's extraction: N = C B with B the trivariate Bernstein polynomials (u fastest).
int cell_values(const Volume& v, const std::array<double, 3>& x, Eigen::VectorXd& values) {
  std::array<int, 3> e{};
  for (int k = 0; k < 3; ++k) {
    const auto spans = v.bases[k].element_spans();
    const int span = v.bases[k].find_span(x[k]);
    e[k] = static_cast<int>(std::find(spans.begin(), spans.end(), span) - spans.begin());
  }
  const int c = e[0] + v.elements[0] * (e[1] + v.elements[1] * e[2]);
  const BezierCell& cell = v.mesh.cell(c);
  const double lo[3] = {cell.u0, cell.v0, cell.w0}, hi[3] = {cell.u1, cell.v1, cell.w1};
  std::array<std::vector<double>, 3> b;
  for (int k = 0; k < 3; ++k) b[k] = bernstein(v.p[k], (x[k] - lo[k]) / (hi[k] - lo[k]));
  Eigen::VectorXd B(cell.num_bernstein());
  for (int ci = 0; ci <= v.p[2]; ++ci)
    for (int bi = 0; bi <= v.p[1]; ++bi)
      for (int ai = 0; ai <= v.p[0]; ++ai)
        B[ai + (v.p[0] + 1) * (bi + (v.p[1] + 1) * ci)] = b[0][ai] * b[1][bi] * b[2][ci];
  values = v.mesh.extraction(c) * B;
  return c;
}

}  // namespace

TEST_CASE("Trivariate tensor cells: counts, parameter boxes, functions and boundary sides", "[volume]") {
  const Volume v = make_volume({2, 3, 1}, {3, 2, 4}, {1, 1, 0});
  const BezierMesh& mesh = v.mesh;
  REQUIRE(mesh.num_cells() == 3 * 2 * 4);
  const int n[3] = {expected_functions(2, 3, 1), expected_functions(3, 2, 1), expected_functions(1, 4, 0)};
  for (int k = 0; k < 3; ++k) CHECK(v.bases[k].num_functions() == n[k]);
  CHECK(mesh.boundary_names() == std::vector<std::string>{"1", "2", "3", "4", "5", "6"});
  std::vector<int> used(mesh.num_functions(), 0);
  std::array<int, 6> on_side{};
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    const int e[3] = {c % 3, (c / 3) % 2, c / 6};
    CHECK(cell.dimension == 3);
    CHECK(cell.num_sides() == 6);
    CHECK((cell.index_u == e[0] && cell.index_v == e[1] && cell.index_w == e[2]));
    CHECK(cell.u0 == Approx(e[0] / 3.0).margin(1e-15));
    CHECK(cell.v1 == Approx((e[1] + 1) / 2.0).margin(1e-15));
    CHECK(cell.w0 == Approx(e[2] / 4.0).margin(1e-15));
    CHECK((cell.degree_u == 2 && cell.degree_v == 3 && cell.degree_w == 1));
    const auto f = mesh.functions(c);
    REQUIRE(f.size() == 3u * 4 * 2);
    for (int id : f) {
      REQUIRE((id >= 0 && id < mesh.num_functions()));
      ++used[id];
    }
    // Sides u = 0, u = 1, v = 0, v = 1, w = 0, w = 1 carry the ids 0..5 on the domain's boundary.
    const CellSide side_of_id[6] = {kSideLeft, kSideRight, kSideBottom, kSideTop, kSideFront, kSideBack};
    const bool on_boundary[6] = {e[0] == 0, e[0] == 2, e[1] == 0, e[1] == 1, e[2] == 0, e[2] == 3};
    for (int id = 0; id < 6; ++id) {
      CHECK(cell.boundary[side_of_id[id]] == (on_boundary[id] ? id : -1));
      on_side[id] += on_boundary[id];
    }
  }
  // Every function lives on some cell; each face holds as many cells as its grid has.
  CHECK(std::count(used.begin(), used.end(), 0) == 0);
  CHECK(on_side == std::array<int, 6>{8, 8, 12, 12, 6, 6});
  // Uniform knots: the pool holds one matrix per tuple of distinct univariate extractions.
  CHECK(mesh.num_distinct_extractions() <= mesh.num_cells());
}

TEST_CASE("Trivariate tensor B-splines are a linearly independent partition of unity", "[volume]") {
  for (const auto& [p, elements, r] :
       std::vector<std::tuple<std::array<int, 3>, std::array<int, 3>, std::array<int, 3>>>{
           {{1, 1, 1}, {2, 2, 2}, {0, 0, 0}}, {{2, 2, 2}, {3, 3, 3}, {1, 1, 1}}, {{3, 2, 4}, {2, 3, 2}, {1, 0, 2}}}) {
    const Volume v = make_volume(p, elements, r);
    // Each univariate extraction's columns sum to 1 within their own rounding, measured here;
    // a Kronecker column's sum is the product of three such sums, formed with (p+1)^3 more
    // roundings of numbers in [0, 1].
    double univariate = 0;
    for (const auto& basis : v.bases)
      for (const Eigen::MatrixXd& C : bezier_extraction(basis))
        univariate = std::max(univariate, (C.colwise().sum().array() - 1).abs().maxCoeff());
    const int bernstein = (p[0] + 1) * (p[1] + 1) * (p[2] + 1);
    const double bound = 3 * univariate + 4 * bernstein * eps;
    INFO("degrees " << p[0] << p[1] << p[2] << ", univariate column sums within " << univariate);
    CHECK(partition_of_unity_error(v.mesh) <= bound);
    CHECK(bezier_rank(v.mesh) == v.mesh.num_functions());
  }
}

TEST_CASE("Trivariate tensor B-splines equal products of univariate ones and satisfy Marsden's identity", "[volume]") {
  const Volume v = make_volume({2, 3, 2}, {3, 2, 3}, {1, 2, 0});
  const int n[3] = {v.bases[0].num_functions(), v.bases[1].num_functions(), v.bases[2].num_functions()};
  std::array<std::vector<double>, 3> greville;
  for (int k = 0; k < 3; ++k) greville[k] = greville_abscissae(v.bases[k]);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Both routes sum at most (p+1)^3 nonnegative products of numbers in [0, 1] whose sum is at
  // most 1 (B-splines and Bernstein polynomials are nonnegative; the extraction is too).
  const double tolerance = 16 * 3 * 4 * 3 * eps;
  Eigen::VectorXd values;
  for (int trial = 0; trial < 200; ++trial) {
    const std::array<double, 3> x{uniform(random), uniform(random), uniform(random)};
    const int c = cell_values(v, x, values);
    const auto ids = v.mesh.functions(c);
    // De Boor: the p+1 univariate B-splines nonzero at x_k, functions span - p .. span.
    std::array<std::vector<double>, 3> univariate;
    std::array<int, 3> span{};
    for (int k = 0; k < 3; ++k) {
      span[k] = v.bases[k].find_span(x[k]);
      univariate[k].resize(v.p[k] + 1);
      v.bases[k].evaluate(span[k], x[k], univariate[k].data());
    }
    double u_h = 0, sum = 0;
    for (size_t a = 0; a < ids.size(); ++a) {
      const int id = ids[a], i = id % n[0], j = (id / n[0]) % n[1], k = id / (n[0] * n[1]);
      const int li = i - (span[0] - v.p[0]), lj = j - (span[1] - v.p[1]), lk = k - (span[2] - v.p[2]);
      const bool alive = li >= 0 && li <= v.p[0] && lj >= 0 && lj <= v.p[1] && lk >= 0 && lk <= v.p[2];
      const double product = alive ? univariate[0][li] * univariate[1][lj] * univariate[2][lk] : 0.0;
      INFO("point " << x[0] << ", " << x[1] << ", " << x[2] << ", function " << id);
      CHECK(std::abs(values[a] - product) <= tolerance);
      // Marsden: f(u, v, w) = u + 2v - 3w + uvw, linear in each variable, has the B-spline
      // coefficients f(greville_i, greville_j, greville_k).
      const double gi = greville[0][i], gj = greville[1][j], gk = greville[2][k];
      u_h += (gi + 2 * gj - 3 * gk + gi * gj * gk) * values[a];
      sum += values[a];
    }
    CHECK(std::abs(sum - 1) <= tolerance);
    const double f = x[0] + 2 * x[1] - 3 * x[2] + x[0] * x[1] * x[2];
    // |coefficients| <= 7 times the values' rounding, plus the sum's.
    CHECK(std::abs(u_h - f) <= 7 * tolerance + 8 * ids.size() * eps);
  }
}

TEST_CASE("A BezierMesh refuses what is not a grid of quadrilaterals or of hexahedra", "[volume]") {
  Volume v = make_volume({1, 1, 1}, {2, 2, 2}, {0, 0, 0});
  CHECK_THROWS_AS(add_tensor_cells(v.mesh, v.bases, 0, 3), std::logic_error);  // slabs beyond the grid
  // A quadrilateral added to a mesh of hexahedra.
  BezierCell quad;
  const int id = v.mesh.add_extraction(Eigen::MatrixXd::Identity(4, 4));
  const std::vector<int> four{0, 1, 2, 3};
  CHECK_THROWS_AS(v.mesh.add_cell(quad, four, id), std::logic_error);
  // A hexahedron that claims dimension 2, and one with degree 0 along w.
  BezierMesh fresh;
  const int id8 = fresh.add_extraction(Eigen::MatrixXd::Identity(8, 8));
  const std::vector<int> eight{0, 1, 2, 3, 4, 5, 6, 7};
  BezierCell hexahedron;
  hexahedron.degree_w = 1;
  CHECK_THROWS_AS(fresh.add_cell(hexahedron, eight, id8), std::logic_error);
  hexahedron.dimension = 3;
  fresh.add_cell(hexahedron, eight, id8);
  CHECK(fresh.num_cells() == 1);
  BezierCell flat = hexahedron;
  flat.degree_w = 0;
  CHECK_THROWS_AS(fresh.add_cell(flat, four, fresh.add_extraction(Eigen::MatrixXd::Identity(4, 4))), std::logic_error);
}

namespace {

// A polynomial volume over [0, 1]^3: x = u + v^2/10, y = v, z = w (1 + u/5), of degrees
// (1, 2, 1), one span, its control points the Bernstein coefficients of those polynomials.
// det J = 1 + u/5, so its volume is 11/10.
NurbsVolume polynomial_volume() {
  NurbsVolume volume;
  volume.bases = {BSplineBasis1D(1, {0, 0, 1, 1}), BSplineBasis1D(2, {0, 0, 0, 1, 1, 1}), BSplineBasis1D(1, {0, 0, 1, 1})};
  volume.control_points.resize(12, 3);
  const double v_squared[3] = {0, 0, 1}, v_linear[3] = {0, 0.5, 1};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 2; ++i)
        volume.control_points.row(i + 2 * j + 6 * k) << i + 0.1 * v_squared[j], v_linear[j], k * (1 + 0.2 * i);
  volume.weights.setOnes(12);
  return volume;
}

// The thick quarter annulus r in [1, 2], angle in [0, pi/2], z in [0, 3]: u radial, v the angle
// (two 45-degree arcs, each a rational quadratic with middle weight cos(22.5 degrees)), w the
// height; an interior knot in u and in w too, so that it has 2 x 2 x 2 spans.
NurbsVolume thick_quarter_annulus() {
  NurbsVolume volume;
  volume.bases = {BSplineBasis1D(1, {0, 0, 0.5, 1, 1}), BSplineBasis1D(2, {0, 0, 0, 0.5, 0.5, 1, 1, 1}),
                  BSplineBasis1D(1, {0, 0, 0.5, 1, 1})};
  const double t = std::tan(M_PI / 8), c = std::cos(M_PI / 8), h = std::sqrt(0.5);
  const double arc[5][3] = {{1, 0, 1}, {1, t, c}, {h, h, 1}, {t, 1, c}, {0, 1, 1}};  // x, y on r = 1, weight
  volume.control_points.resize(3 * 5 * 3, 3);
  volume.weights.resize(3 * 5 * 3);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 3; ++i) {
        const int id = i + 3 * (j + 5 * k);
        const double r = 1 + 0.5 * i;
        volume.control_points.row(id) << r * arc[j][0], r * arc[j][1], 1.5 * k;
        volume.weights[id] = arc[j][2];
      }
  return volume;
}

}  // namespace

TEST_CASE("A polynomial NURBS volume on hexahedra: exact volume, positive Jacobians", "[volume]") {
  const NurbsVolume volume = polynomial_volume();
  BezierMesh mesh;
  const std::array<BSplineBasis1D, 3> space{uniform_basis(2, 2, 1), uniform_basis(2, 3, 1), uniform_basis(3, 2, 2)};
  add_tensor_cells(mesh, space, 0, 2);
  mesh.set_num_functions(space[0].num_functions() * space[1].num_functions() * space[2].num_functions());
  const VolumeGeometryMap map(mesh, volume);
  CHECK(map.parametric_dimension() == 3);
  CellBasis cb;
  double total = 0;
  long points = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    evaluate_volume_cell_basis(mesh, map, c, 3, 3, 3, cb);
    CHECK(cb.geometry.parametric_dimension() == 3);
    CHECK(cb.min_jacobian > 0);
    total += cb.measure.sum();
    points += cb.measure.size();
    // The functions' values still sum to 1 and their gradients to 0 after the map.
    CHECK((cb.C * cb.value.transpose()).colwise().sum().maxCoeff() == Approx(1).margin(1e-14));
    for (int d = 0; d < 3; ++d) CHECK((cb.C * cb.grad(d).transpose()).colwise().sum().cwiseAbs().maxCoeff() < 1e-12);
  }
  // det J = 1 + u/5 (a degree-1 polynomial) and the cell's size: 3 Gauss points are exact, and
  // the sum carries one rounding per point and per product.
  CHECK(std::abs(total - 1.1) <= 8 * points * eps);
  // The faces: v = 0 is the plane y = 0 with area element |x_u x x_w| = 1 + u/5 (area 11/10),
  // w = 0 the plane z = 0 with area element 1 (area 1), outward normals -e_y and -e_z; on w = 1
  // the outward normal is x_u x x_v / |x_u x x_v| = (-1/5, v/25, 1) / |...|.
  double bottom = 0, front = 0;
  long face_points = 0;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& cell = mesh.cell(c);
    if (cell.boundary[kSideBottom] == 2) {
      evaluate_side_basis(mesh, map, c, kSideBottom, 3, cb);
      bottom += cb.measure.sum();
      face_points += cb.measure.size();
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k) {
        CHECK(std::abs(cb.geometry.x(k, 1)) <= eps);
        CHECK((cb.normal.row(k) - Eigen::RowVector3d(0, -1, 0)).norm() <= 8 * eps);
      }
    }
    if (cell.boundary[kSideFront] == 4) {
      evaluate_side_basis(mesh, map, c, kSideFront, 3, cb);
      front += cb.measure.sum();
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k)
        CHECK((cb.normal.row(k) - Eigen::RowVector3d(0, 0, -1)).norm() <= 8 * eps);
    }
    if (cell.boundary[kSideBack] == 5) {
      evaluate_side_basis(mesh, map, c, kSideBack, 3, cb);
      for (Eigen::Index k = 0; k < cb.measure.size(); ++k) {
        const double v = cb.geometry.x(k, 1);  // y = v
        CHECK((cb.normal.row(k) - Eigen::RowVector3d(-0.2, 0.04 * v, 1).normalized()).norm() <= 16 * eps);
      }
    }
  }
  CHECK(std::abs(bottom - 1.1) <= 8 * face_points * eps);
  CHECK(std::abs(front - 1.0) <= 8 * face_points * eps);
  CHECK(side_bernstein_indices(2, 3, 1, kSideBack).size() == 12u);
  CHECK(side_bernstein_indices(2, 3, 1, kSideLeft) == std::vector<int>{0, 3, 6, 9, 12, 15, 18, 21});
}

TEST_CASE("The isoparametric identity on a thick quarter annulus: x, y, z and their gradients reproduced", "[volume]") {
  const NurbsVolume volume = thick_quarter_annulus();
  BezierMesh mesh;
  add_tensor_cells(mesh, volume.bases, 0, 2);
  mesh.set_num_functions(static_cast<int>(volume.weights.size()));
  mesh.set_weights(volume.weights);
  const VolumeGeometryMap map(mesh, volume);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Eigen::VectorXd u(20), v(20), w(20);
  CellBasis cb;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    for (int k = 0; k < 20; ++k) u[k] = uniform(random), v[k] = uniform(random), w[k] = uniform(random);
    evaluate_volume_cell_basis_at(mesh, map, c, u, v, w, cb);
    CHECK(cb.min_jacobian > 0);  // u radial, v counter-clockwise, w up: a right-handed map
    const auto ids = mesh.functions(c);
    for (Eigen::Index k = 0; k < u.size(); ++k) {
      const Eigen::VectorXd R = cb.C * cb.value.row(k).transpose();
      // The point lies on the annulus: radius in [1, 2], the first quadrant, height in [0, 3].
      const Eigen::Vector3d x = cb.geometry.x.row(k).transpose();
      CHECK(std::hypot(x[0], x[1]) == Approx(1 + u[k] * 0.5 + 0.5 * (c % 2)).margin(1e-14));
      CHECK(x[2] == Approx(1.5 * (w[k] + c / 4)).margin(1e-14));
      Eigen::Matrix3d J;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) J(i, j) = cb.geometry.jacobian(k, 3 * i + j);
      // Frobenius norms: at least the 2-norm condition number.
      const double condition = J.norm() * J.inverse().norm();
      for (int d = 0; d < 3; ++d) {
        double value = 0, size = 0;
        Eigen::Vector3d grad = Eigen::Vector3d::Zero(), grad_size = Eigen::Vector3d::Zero();
        for (size_t a = 0; a < ids.size(); ++a) {
          const double coefficient = volume.control_points(ids[a], d);
          value += coefficient * R[a];
          size += std::abs(coefficient * R[a]);
          for (int e = 0; e < 3; ++e) {
            const double g = (e == 0 ? cb.C * cb.grad_x.row(k).transpose()
                                     : e == 1 ? cb.C * cb.grad_y.row(k).transpose() : cb.C * cb.grad_z.row(k).transpose())[a];
            grad[e] += coefficient * g;
            grad_size[e] += std::abs(coefficient * g);
          }
        }
        // sum_i P_i R_i = x (the map's own point) and sum_i P_i grad R_i = e_d: forward error
        // bounds of the sums, the gradients through J^{-T} (its condition number).
        CHECK(std::abs(value - x[d]) <= 32 * eps * (size + std::abs(x[d])));
        for (int e = 0; e < 3; ++e)
          CHECK(std::abs(grad[e] - (e == d ? 1.0 : 0.0)) <= 64 * eps * condition * (grad_size[e] + 1));
      }
    }
  }
}

TEST_CASE("A volume map refuses cells across its knots, and 2D calls on hexahedra are refused", "[volume]") {
  const NurbsVolume volume = thick_quarter_annulus();
  BezierMesh coarse;  // one cell over all of [0, 1]^3, across the volume's interior knots
  const std::array<BSplineBasis1D, 3> one_span{uniform_basis(2, 1, 1), uniform_basis(2, 1, 1), uniform_basis(2, 1, 1)};
  add_tensor_cells(coarse, one_span, 0, 1);
  coarse.set_num_functions(27);
  CHECK_THROWS_AS(VolumeGeometryMap(coarse, volume), GeometryError);
  BezierMesh mesh;
  add_tensor_cells(mesh, volume.bases, 0, 2);
  mesh.set_num_functions(static_cast<int>(volume.weights.size()));
  const VolumeGeometryMap map(mesh, volume);
  CellBasis cb;
  GeometryAtPoints at;
  CHECK_THROWS_AS(evaluate_cell_basis(mesh, map, 0, 2, 2, cb), std::logic_error);
  CHECK_THROWS_AS(map.evaluate_at_rule(0, 2, 2, at), std::logic_error);
  NurbsVolume broken = volume;
  broken.weights[3] = -1;
  CHECK_THROWS_AS(broken.validate(), std::invalid_argument);
  broken = volume;
  broken.control_points.conservativeResize(10, 3);
  CHECK_THROWS_AS(broken.validate(), std::invalid_argument);
}

namespace {

// Halving h divides the L2 error by about 2^(p+1) and the H1-seminorm error by 2^p
// (quasi-uniform meshes, a smooth solution); the measured rates may fall short of these by the
// pre-asymptotic part, for which 0.2 is allowed. `errors(p, n)`: the errors on n^3 elements.
template <class ErrorsOn>
void check_optimal_rates(const std::vector<std::pair<int, int>>& levels, ErrorsOn errors) {
  for (const auto& [p, n] : levels) {
    const ErrorNorms coarse = errors(p, n), fine = errors(p, 2 * n);
    const double l2_rate = std::log2(coarse.l2 / fine.l2), h1_rate = std::log2(coarse.h1_semi / fine.h1_semi);
    INFO("p = " << p << ", " << n << " -> " << 2 * n << " elements per direction: L2 " << coarse.l2 << " -> " << fine.l2
                << " (rate " << l2_rate << "), H1 " << coarse.h1_semi << " -> " << fine.h1_semi << " (rate " << h1_rate
                << ")");
    CHECK(l2_rate >= p + 1 - 0.2);
    CHECK(h1_rate >= p - 0.2);
  }
}

// The unit cube as a trilinear volume (its eight corners).
NurbsVolume unit_cube() {
  NurbsVolume volume;
  volume.bases = {BSplineBasis1D(1, {0, 0, 1, 1}), BSplineBasis1D(1, {0, 0, 1, 1}), BSplineBasis1D(1, {0, 0, 1, 1})};
  volume.control_points.resize(8, 3);
  for (int k = 0; k < 8; ++k) volume.control_points.row(k) << k % 2, (k / 2) % 2, k / 4;
  volume.weights.setOnes(8);
  return volume;
}

// The cells and functions of the C^(p-1) space of degree p on n^3 equal elements of [0, 1]^3.
void add_cube_cells(BezierMesh& mesh, int p, int n) {
  const std::array<BSplineBasis1D, 3> space{uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1)};
  add_tensor_cells(mesh, space, 0, n);
  const int m = space[0].num_functions();
  mesh.set_num_functions(m * m * m);
}

// -Laplace u = 3 pi^2 u on the unit cube with u = sin(pi x) sin(pi y) sin(pi z) = 0 on its
// boundary: degree p, n^3 elements, C^(p-1). The boundary functions (first or last in some
// direction: open knots) are fixed at 0; the system is solved by a sparse Cholesky factorization,
// and the errors integrated here with p + 2 Gauss points per direction.
ErrorNorms cube_errors(int p, int n) {
  BezierMesh mesh;
  const std::array<BSplineBasis1D, 3> space{uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1)};
  add_tensor_cells(mesh, space, 0, n);
  const int m = space[0].num_functions();
  mesh.set_num_functions(m * m * m);
  const VolumeGeometryMap map(mesh, unit_cube());
  std::vector<bool> fixed(m * m * m);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        fixed[i + m * (j + m * k)] = i == 0 || j == 0 || k == 0 || i == m - 1 || j == m - 1 || k == m - 1;
  const DofLayout layout = make_dof_layout(m * m * m, fixed);
  const Expression source = Expression::parse("3*pi^2*sin(pi*x)*sin(pi*y)*sin(pi*z)", "test");
  PoissonForm form;
  form.source = &source;
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(mesh, layout);
  Eigen::VectorXd rhs;
  assemble_poisson(mesh, map, form, layout, Eigen::VectorXd::Zero(m * m * m), QuadratureOptions{}, K, rhs);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver(K);
  REQUIRE(solver.info() == Eigen::Success);
  const Eigen::VectorXd free = solver.solve(rhs);
  Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(m * m * m);
  for (int d = 0; d < layout.num_free(); ++d) coefficients[layout.function_of_dof[d]] = free[d];
  ErrorNorms e;
  CellBasis cb;
  for (int c = 0; c < mesh.num_cells(); ++c) {
    evaluate_volume_cell_basis(mesh, map, c, p + 2, p + 2, p + 2, cb);
    const auto ids = mesh.functions(c);
    Eigen::VectorXd local(ids.size());
    for (size_t a = 0; a < ids.size(); ++a) local[a] = coefficients[ids[a]];
    const Eigen::VectorXd bernstein = cb.C.transpose() * local;
    const Eigen::VectorXd u_h = cb.value * bernstein;
    for (Eigen::Index q = 0; q < cb.measure.size(); ++q) {
      const double x = cb.geometry.x(q, 0), y = cb.geometry.x(q, 1), z = cb.geometry.x(q, 2);
      const double sx = std::sin(M_PI * x), sy = std::sin(M_PI * y), sz = std::sin(M_PI * z);
      const double cx = std::cos(M_PI * x), cy = std::cos(M_PI * y), cz = std::cos(M_PI * z);
      const double exact[4] = {sx * sy * sz, M_PI * cx * sy * sz, M_PI * sx * cy * sz, M_PI * sx * sy * cz};
      e.l2 += cb.measure[q] * std::pow(u_h[q] - exact[0], 2);
      for (int d = 0; d < 3; ++d) e.h1_semi += cb.measure[q] * std::pow(cb.grad(d).row(q).dot(bernstein) - exact[1 + d], 2);
    }
  }
  e.l2 = std::sqrt(e.l2);
  e.h1_semi = std::sqrt(e.h1_semi);
  return e;
}

}  // namespace

TEST_CASE("Poisson on the unit cube through the one assembler: optimal rates for p = 1, 2, 3", "[volume]") {
  check_optimal_rates({{1, 4}, {2, 4}, {3, 3}}, cube_errors);
}

namespace {

// -Laplace u = f on a volume, u (a function of x, y, z) on all six faces by projection. f is
// written out by hand in the tests that give it, so that the symbolic derivation is not what
// they test; "" derives it (differentiate_volume_solution).
PoissonProblem dirichlet_problem(const std::string& u, const std::string& f) {
  PoissonProblem problem;
  problem.exact = differentiate_volume_solution(Expression::parse(u, "test: exact"));
  problem.source = f.empty() ? problem.exact->minus_laplacian : Expression::parse(f, "test: source");
  problem.boundary.assign(6, BoundaryCondition{});  // Dirichlet from the exact solution
  return problem;
}

struct CubeSolve {
  ErrorNorms errors;
  double stiffness_condition = 0, boundary_mass_condition = 0;
  ErrorNorms driver_errors;  // the same problem through solve_poisson (CHOLMOD)
};

// -Laplace u = f on the unit cube, u given on all six faces (imposed by the L2 projection of u
// onto the faces' traces: dirichlet_pieces, solve_dirichlet_projection), degree p, n^3
// elements, C^(p-1); the errors by error_norms; the 2-norm condition numbers of the free
// stiffness and of the faces' mass matrix (dense eigenvalues: the meshes here are small).
CubeSolve solve_cube(int p, int n, const std::string& u, const std::string& f, bool conditions) {
  BezierMesh mesh;
  const std::array<BSplineBasis1D, 3> space{uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1), uniform_basis(p, n, p - 1)};
  add_tensor_cells(mesh, space, 0, n);
  const int m = space[0].num_functions(), functions = m * m * m;
  mesh.set_num_functions(functions);
  const VolumeGeometryMap map(mesh, unit_cube());
  const PoissonProblem problem = dirichlet_problem(u, f);
  const QuadratureOptions quadrature;
  const DirichletPieces pieces = dirichlet_pieces(mesh, map, problem, quadrature, CellRange{}, MeshPart{});
  Eigen::VectorXd fixed_values = Eigen::VectorXd::Zero(functions);
  std::vector<bool> fixed(functions, false);
  for (const auto& [function, value] : solve_dirichlet_projection(pieces)) fixed[function] = true, fixed_values[function] = value;
  // Exactly the functions on the boundary (first or last along some direction) are fixed.
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        REQUIRE(fixed[i + m * (j + m * k)] == (i == 0 || j == 0 || k == 0 || i == m - 1 || j == m - 1 || k == m - 1));
  const DofLayout layout = make_dof_layout(functions, fixed);
  PoissonForm form;
  form.source = &problem.source;
  Eigen::SparseMatrix<double> K = lower_pattern_matrix(mesh, layout);
  Eigen::VectorXd rhs;
  assemble_poisson(mesh, map, form, layout, fixed_values, quadrature, K, rhs);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver(K);
  REQUIRE(solver.info() == Eigen::Success);
  const Eigen::VectorXd free = solver.solve(rhs);
  Eigen::VectorXd coefficients = fixed_values;
  for (int d = 0; d < layout.num_free(); ++d) coefficients[layout.function_of_dof[d]] = free[d];
  CubeSolve out;
  out.errors = error_norms(mesh, map, coefficients, *problem.exact, quadrature);
  const PoissonSolution driven = solve_poisson(mesh, map, problem, PoissonSolveOptions{});
  REQUIRE(driven.errors);
  out.driver_errors = *driven.errors;
  if (conditions) {
    const Eigen::MatrixXd dense = Eigen::MatrixXd(K).selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd k = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(dense).eigenvalues();
    out.stiffness_condition = k.maxCoeff() / k.minCoeff();
    std::vector<int> ids = pieces.functions;
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(ids.size()), static_cast<Eigen::Index>(ids.size()));
    const auto at = [&](int f) { return std::lower_bound(ids.begin(), ids.end(), f) - ids.begin(); };
    for (const auto& t : pieces.mass) M(at(t.row()), at(t.col())) += t.value();
    const Eigen::VectorXd b = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues();
    out.boundary_mass_condition = b.maxCoeff() / b.minCoeff();
  }
  return out;
}

}  // namespace

TEST_CASE("Poisson on the unit cube with Dirichlet data projected on the faces: optimal rates", "[volume]") {
  // u = exp(x/2) sin(y + 1) cos(z): Laplace u = (1/4 - 2) u.
  const std::string u = "exp(x/2)*sin(y+1)*cos(z)", f = "1.75*exp(x/2)*sin(y+1)*cos(z)";
  check_optimal_rates({{1, 4}, {2, 3}, {3, 3}}, [&](int p, int n) { return solve_cube(p, n, u, f, false).errors; });
  // The driver (solve_poisson: the projection, the one assembler, CHOLMOD, error_norms) solves
  // the same discrete problem as the test's own steps with Eigen's LDL^T: the same errors up to
  // the two factorizations' rounding, at most cond K times eps relative to |u_h| <= e^(1/2).
  const CubeSolve s = solve_cube(2, 3, u, f, true);
  const double rounding = 64 * eps * std::exp(0.5) * s.stiffness_condition;
  CHECK(std::abs(s.driver_errors.l2 - s.errors.l2) <= rounding);
  CHECK(std::abs(s.driver_errors.h1_semi - s.errors.h1_semi) <= rounding * s.stiffness_condition);
}

TEST_CASE("The patch test on the unit cube: a trilinear u is reproduced to rounding", "[volume]") {
  // u = 1 + x + 2y - z + xyz is in every space of degree >= 1 on the cube (linear in each
  // variable) and harmonic: the projection on the faces and the solve reproduce it. The error
  // is rounding, bounded by the conditioning of the two systems: |u| <= 6 on the cube, each
  // solve loses at most its condition number in relative accuracy.
  for (const auto& [p, n] : std::vector<std::pair<int, int>>{{1, 3}, {2, 3}, {3, 2}}) {
    const CubeSolve s = solve_cube(p, n, "1 + x + 2*y - z + x*y*z", "0", true);
    const double bound = 64 * eps * 6 * s.stiffness_condition * (1 + s.boundary_mass_condition);
    INFO("p = " << p << ": L2 " << s.errors.l2 << ", H1 " << s.errors.h1_semi << ", bound " << bound << " (cond K "
                << s.stiffness_condition << ", cond M " << s.boundary_mass_condition << ")");
    CHECK(s.errors.l2 <= bound);
    CHECK(s.driver_errors.l2 <= bound);
    // The seminorm by the inverse inequality, |e|_1 <= C h^-1 |e|_0 with h^-2 ~ cond K.
    CHECK(s.errors.h1_semi <= bound * s.stiffness_condition);
  }
  // Through the driver, with the suite's bound from the solve's own condition estimates
  // (rounding_bounds.hpp: Lanczos on the Jacobi-scaled stiffness and mass matrices).
  BezierMesh mesh;
  add_cube_cells(mesh, 2, 3);
  const VolumeGeometryMap map(mesh, unit_cube());
  const PoissonProblem problem = dirichlet_problem("1 + x + 2*y - z + x*y*z", "0");
  const rounding_test::Reproduction r = rounding_test::solve_reproducing(mesh, map, problem);
  INFO("L2 " << r.errors.l2 << " (bound " << r.l2_bound() << "), H1 " << r.errors.h1_semi << " (bound " << r.h1_bound()
             << "), kappa K " << r.kappa_stiffness << ", kappa M " << r.kappa_mass);
  CHECK(r.reproduced());
}

namespace {

// Degree p on [0, 1], n equal elements (n even), C^(p-1) except C^0 at 1/2 when `c0_half`.
BSplineBasis1D basis_with_half(int p, int n, bool c0_half) {
  std::vector<double> knots(p + 1, 0.0);
  for (int e = 1; e < n; ++e) knots.insert(knots.end(), 2 * e == n && c0_half ? p : 1, double(e) / n);
  knots.insert(knots.end(), p + 1, 1.0);
  return BSplineBasis1D(p, knots);
}

// u = sin(x) e^(y/2) (1 + z^2/9): Laplace u = (-1 + 1/4) u + sin(x) e^(y/2) 2/9.
PoissonProblem annulus_problem() {
  return dirichlet_problem("sin(x)*exp(y/2)*(1+z^2/9)", "0.75*sin(x)*exp(y/2)*(1+z^2/9) - 2/9*sin(x)*exp(y/2)");
}

// `problem` on the thick quarter annulus (its NURBS map, evaluated as given on every cell) with
// a B-spline space of degree p on n^3 elements (the angle's knot 1/2, where the map is only
// C^0, kept C^0); solve_poisson's errors.
ErrorNorms annulus_errors(int p, int n, const PoissonProblem& problem) {
  const NurbsVolume volume = thick_quarter_annulus();
  const std::array<BSplineBasis1D, 3> space{basis_with_half(p, n, false), basis_with_half(p, n, true),
                                            basis_with_half(p, n, false)};
  BezierMesh mesh;
  add_tensor_cells(mesh, space, 0, n);
  mesh.set_num_functions(space[0].num_functions() * space[1].num_functions() * space[2].num_functions());
  const VolumeGeometryMap map(mesh, volume);
  const PoissonSolution solution = solve_poisson(mesh, map, problem, PoissonSolveOptions{});
  REQUIRE(solution.errors);
  return *solution.errors;
}

}  // namespace

TEST_CASE("Poisson on the thick quarter annulus (NURBS geometry, B-spline space): optimal rates", "[volume]") {
  // At p = 3 the step 4 -> 8 is still pre-asymptotic (measured: 3.57, 2.66, 4.36 in L2 from 2
  // to 16 elements per direction, H1 3.00, 2.28, 3.24): the rates are taken from 8 to 16.
  check_optimal_rates({{1, 4}, {2, 4}, {3, 8}}, [](int p, int n) { return annulus_errors(p, n, annulus_problem()); });
}

TEST_CASE("Neumann data on a volume's faces: optimal rates on the thick quarter annulus", "[volume]") {
  // The outer cylinder (u = 1, side "2") and the top (w = 1, side "6") take the flux grad u . n
  // of the exact solution, the other four faces its values. Only the data change; the rates
  // must stay p + 1 and p.
  PoissonProblem problem = annulus_problem();
  problem.boundary[1].kind = problem.boundary[5].kind = BoundaryKind::kNeumann;
  check_optimal_rates({{1, 4}, {2, 4}, {3, 8}}, [&](int p, int n) { return annulus_errors(p, n, problem); });
  // The same flux given as a vector F = grad u (three components) is the same data.
  PoissonProblem vector_flux = problem;
  for (int side : {1, 5}) {
    vector_flux.boundary[side].from_exact = false;
    vector_flux.boundary[side].flux = {problem.exact->u_x, problem.exact->u_y, problem.exact->u_z};
  }
  const ErrorNorms a = annulus_errors(2, 4, problem), b = annulus_errors(2, 4, vector_flux);
  CHECK(a.l2 == b.l2);
  CHECK(a.h1_semi == b.h1_semi);
  // A planar flux vector (two components) is refused on a volume, naming its field.
  vector_flux.boundary[1].flux.pop_back();
  CHECK_THROWS_WITH(annulus_errors(1, 2, vector_flux), Catch::Contains("a flux vector has 3 components here, got 2"));
}

TEST_CASE("Nitsche's method on a volume's faces: optimal rates, and the patch test", "[volume]") {
  // Dirichlet data on every face imposed weakly (the penalty from each boundary cell's own
  // eigenvalue bound): the rates p + 1 and p of the projection.
  PoissonProblem problem = annulus_problem();
  problem.dirichlet_method = DirichletMethod::kNitsche;
  check_optimal_rates({{1, 4}, {2, 4}, {3, 8}}, [&](int p, int n) { return annulus_errors(p, n, problem); });
  // A trilinear harmonic u is in the space: Nitsche's consistent form reproduces it, to the
  // suite's rounding bound (the solve's own condition estimates).
  BezierMesh mesh;
  add_cube_cells(mesh, 2, 3);
  const VolumeGeometryMap map(mesh, unit_cube());
  PoissonProblem trilinear = dirichlet_problem("1 + x + 2*y - z + x*y*z", "0");
  trilinear.dirichlet_method = DirichletMethod::kNitsche;
  trilinear.boundary[3].kind = BoundaryKind::kNeumann;  // and a Neumann face
  const rounding_test::Reproduction r = rounding_test::solve_reproducing(mesh, map, trilinear);
  INFO("L2 " << r.errors.l2 << " (bound " << r.l2_bound() << "), H1 " << r.errors.h1_semi << " (bound " << r.h1_bound() << ")");
  CHECK(r.reproduced());
}

TEST_CASE("The general form on a volume, A a symmetric 3x3 matrix of functions and c a function: optimal rates", "[volume]") {
  // A positive definite everywhere on the annulus (diagonally dominant), c = 1 + z; f derived
  // symbolically in three dimensions, and the Neumann face's data the conormal flux (A grad u).n.
  PoissonProblem problem = dirichlet_problem("sin(x)*exp(y/2)*(1+z^2/9)", "");
  problem.coefficients.diffusion = {Expression::parse("2 + x", "a11"), Expression::parse("x*y/10", "a12"),
                                    Expression::parse("0.3", "a13"),   Expression::parse("2 + z/3", "a22"),
                                    Expression::parse("-0.2", "a23"),  Expression::parse("1.5", "a33")};
  problem.coefficients.reaction = Expression::parse("1 + z", "c");
  problem.source = derive_general_source(problem.exact->u, problem.coefficients.diffusion, problem.coefficients.reaction, 0, 3);
  problem.boundary[5].kind = BoundaryKind::kNeumann;
  check_optimal_rates({{1, 4}, {2, 4}}, [&](int p, int n) { return annulus_errors(p, n, problem); });
  // The derived f against one written out by hand, at points of the annulus: with
  // a12 = a13 = a23 = 0, a11 = a22 = a33 = 2 and c = 1, f = -2 Laplace u + u. The two programs
  // round differently, each within a few ulps of the sum of its terms' magnitudes.
  const Expression derived = derive_general_source(problem.exact->u, {Expression::parse("2", "a")}, Expression(), 1, 3);
  ExpressionEvaluator f(derived);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int k = 0; k < 50; ++k) {
    const double r = 1 + unit(random), angle = M_PI / 2 * unit(random), x = r * std::cos(angle), y = r * std::sin(angle),
                 z = 3 * unit(random);
    const double se = std::sin(x) * std::exp(y / 2), g = 1 + z * z / 9;
    const double terms[3] = {2 * 0.75 * se * g, -2 * 2.0 / 9 * se, se * g};
    const double magnitude = std::abs(terms[0]) + std::abs(terms[1]) + std::abs(terms[2]);
    CHECK(std::abs(f(x, y, z) - (terms[0] + terms[1] + terms[2])) <= 64 * eps * magnitude);
  }
  // A matrix that is not positive definite at some point is refused, naming it.
  problem.coefficients.diffusion[1] = Expression::parse("3", "a12");
  CHECK_THROWS_WITH(annulus_errors(1, 2, problem), Catch::Contains("is not positive definite at ("));
}

TEST_CASE("A volume solved by CG without a matrix gives the direct solve's errors", "[volume]") {
  // The unit cube, u = sin(x) y^2 z, degree 2 on 3^3 elements: the errors of CG on the
  // operator alone (AffineVolumeOperator) against those of CHOLMOD on the assembled matrix.
  BezierMesh mesh;
  add_cube_cells(mesh, 2, 3);
  const VolumeGeometryMap map(mesh, unit_cube());
  const PoissonProblem problem = dirichlet_problem("sin(x)*y*y*z", "-(-sin(x)*y*y*z + 2*sin(x)*z)");
  PoissonSolveOptions with_matrix;
  Eigen::MatrixXd K;
  with_matrix.on_system = [&K](const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXd&) {
    K = Eigen::MatrixXd(lower).selfadjointView<Eigen::Lower>();
  };
  const PoissonSolution direct = solve_poisson(mesh, map, problem, with_matrix);
  REQUIRE(direct.errors);
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues();
  const double kappa = lambda[lambda.size() - 1] / lambda[0];
  const std::array<BSplineBasis1D, 3> space{uniform_basis(2, 3, 1), uniform_basis(2, 3, 1), uniform_basis(2, 3, 1)};
  const std::shared_ptr<const MatrixFreePoisson> op =
      std::make_shared<AffineVolumeOperator>(space, *affine_map(unit_cube()), 1.0, 0.0);
  PoissonSolveOptions without_matrix;
  without_matrix.iterative = true;
  without_matrix.matrix_free = [op] { return op; };
  const PoissonSolution cg = solve_poisson(mesh, map, problem, without_matrix);
  REQUIRE(cg.errors);
  CHECK(cg.assembly == "none");
  // Both solve the same system (K's entries equal to rounding: test_affine_volume_operator), CG
  // to a backward error of 1e-15, CHOLMOD backward stably: the coefficients differ by about
  // kappa (1e-15 + eps) relative (kappa from K's eigenvalues), the errors by at most that times
  // the solution's size (|u|_L2 < 1, |u|_H1 < 10 here).
  INFO("kappa " << kappa);
  const double bound = 10 * kappa * (1e-15 + eps);
  CHECK(std::abs(cg.errors->l2 - direct.errors->l2) <= bound);
  CHECK(std::abs(cg.errors->h1_semi - direct.errors->h1_semi) <= 10 * bound);
  // A driver given no operator is a programming error, said as one.
  without_matrix.matrix_free = [] { return std::shared_ptr<const MatrixFreePoisson>(); };
  CHECK_THROWS_WITH(solve_poisson(mesh, map, problem, without_matrix), Catch::Contains("matrix_free gave no operator"));
}
