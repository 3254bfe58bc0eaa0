// Trivariate tensor-product B-splines as hexahedral cells of a BezierMesh (add_tensor_cells in
// three directions), checked by properties that do not depend on the construction: counts from
// the knot vectors, partition of unity, linear independence, values against products of
// univariate B-splines evaluated by de Boor's recurrence, and Marsden's identity.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "basis/core/bezier_mesh_checks.hpp"
#include "basis/core/bspline_basis.hpp"
#include "basis/tensor/tensor_patch.hpp"

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
