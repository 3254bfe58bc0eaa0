#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "basis/tensor/tensor_patch.hpp"
#include "cases/geometries.hpp"
#include "quadrature/bernstein.hpp"
#include "solver/cell_basis.hpp"
#include "basis/core/geometry_map.hpp"

using namespace knotwork;

namespace {
// The tensor family's map: the patch on the grid of the space's elements.
PatchGeometryMap::ElementGrid grid_of(const TensorDiscretization& d) {
  return {d.space_u.breakpoints(), d.space_v.breakpoints(), d.first_row};
}

// 20 Gauss points per direction: det J of a rational map is not a polynomial, so the
// area is exact only up to a quadrature error that this many points push below roundoff.
double area(const TensorDiscretization& d, const GeometryMap& g) {
  double a = 0;
  CellBasis cb;
  for (int c = 0; c < d.mesh.num_cells(); ++c) {
    evaluate_cell_basis(d.mesh, g, c, 20, 20, cb);
    a += cb.measure.sum();
  }
  return a;
}
}  // namespace

TEST_CASE("The quarter annulus stays exactly on its circles under k-refinement", "[geometry]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(0, 1);
  for (int p = 2; p <= 5; ++p)
    for (int n : {1, 3, 7}) {
      TensorSpaceOptions o;
      o.degree = {p, p};
      o.elements_per_span = {n, n};
      const TensorDiscretization disc = build_tensor_discretization(quarter_annulus_patch(1, 2), o);
      PatchGeometryMap g(disc.mesh, disc.patch, grid_of(disc));
      for (int c = 0; c < disc.mesh.num_cells(); ++c) {
        Eigen::VectorXd u(4), v(4);
        for (int k = 0; k < 4; ++k) { u[k] = d(rng); v[k] = d(rng); }
        u[0] = 0; v[1] = 1;
        GeometryAtPoints at;
        g.evaluate(c, u, v, at);
        const BezierCell& cell = disc.mesh.cell(c);
        for (int k = 0; k < 4; ++k) {
          // x(u, v) = (1 + u) * (point on the unit quarter circle): |x| = 1 + u exactly.
          const double radius = 1.0 + cell.u0 + u[k] * (cell.u1 - cell.u0);
          REQUIRE(std::abs(at.x.row(k).norm() - radius) < 1e-14);
          REQUIRE(at.x(k, 0) >= -1e-15);
          REQUIRE(at.x(k, 1) >= -1e-15);
        }
      }
      INFO("p = " << p << ", n = " << n);
      REQUIRE(std::abs(area(disc, g) - 0.75 * std::numbers::pi) < 1e-13);
    }
}

TEST_CASE("Geometry Jacobians match finite differences of the map", "[geometry]") {
  TensorSpaceOptions o;
  o.degree = {3, 3};
  o.elements_per_span = {2, 3};
  const TensorDiscretization disc = build_tensor_discretization(quarter_annulus_patch(0.5, 1.5), o);
  PatchGeometryMap g(disc.mesh, disc.patch, grid_of(disc));
  const double h = 1e-6;
  for (int c = 0; c < disc.mesh.num_cells(); ++c) {
    Eigen::VectorXd u(5), v(5);
    u << 0.5, 0.5 + h, 0.5 - h, 0.5, 0.5;
    v << 0.3, 0.3, 0.3, 0.3 + h, 0.3 - h;
    GeometryAtPoints at;
    g.evaluate(c, u, v, at);
    for (int comp = 0; comp < 2; ++comp) {
      REQUIRE(std::abs(at.jacobian(0, 2 * comp) - (at.x(1, comp) - at.x(2, comp)) / (2 * h)) < 1e-7);
      REQUIRE(std::abs(at.jacobian(0, 2 * comp + 1) - (at.x(3, comp) - at.x(4, comp)) / (2 * h)) < 1e-7);
    }
  }
}

TEST_CASE("Built-in geometries have the right areas and positive Jacobians", "[geometry]") {
  TensorSpaceOptions o;
  o.degree = {2, 2};
  o.elements_per_span = {4, 4};
  {
    const auto d = build_tensor_discretization(lshape_patch(), o);
    PatchGeometryMap g(d.mesh, d.patch, grid_of(d));
    REQUIRE(std::abs(area(d, g) - 3.0) < 1e-13);
    CellBasis cb;
    for (int c = 0; c < d.mesh.num_cells(); ++c) {
      evaluate_cell_basis(d.mesh, g, c, 3, 3, cb);
      REQUIRE(cb.min_jacobian > 0);
    }
  }
  {
    const auto d = build_tensor_discretization(rectangle_patch(-1, 2, 3, 2.5), o);
    PatchGeometryMap g(d.mesh, d.patch, grid_of(d));
    REQUIRE(std::abs(area(d, g) - 2.0) < 1e-14);
  }
}

TEST_CASE("Isoparametric NURBS basis from the BezierMesh: partition of unity and geometry reproduction", "[geometry]") {
  for (int p = 2; p <= 4; ++p) {
    TensorSpaceOptions o;
    o.degree = {p, p};
    o.elements_per_span = {3, 4};
    const auto d = build_tensor_discretization(quarter_annulus_patch(1, 2), o);
    PatchGeometryMap g(d.mesh, d.patch, grid_of(d));
    REQUIRE(d.mesh.is_rational());
    // Control points of the refined geometry: x_i = (w x)_i / w_i.
    const Eigen::MatrixX2d P = d.geometry_homogeneous.leftCols<2>().array().colwise() / d.geometry_homogeneous.col(2).array();
    CellBasis cb;
    for (int c = 0; c < d.mesh.num_cells(); ++c) {
      evaluate_cell_basis(d.mesh, g, c, p + 1, p + 1, cb);
      const Eigen::MatrixXd R = cb.value * cb.C.transpose();  // points x alive functions
      const auto ids = d.mesh.functions(c);
      for (Eigen::Index k = 0; k < R.rows(); ++k) {
        REQUIRE(std::abs(R.row(k).sum() - 1.0) < 1e-14);
        Eigen::RowVector2d x = Eigen::RowVector2d::Zero();
        for (size_t a = 0; a < ids.size(); ++a) x += R(k, a) * P.row(ids[a]);
        REQUIRE((x - cb.geometry.x.row(k)).norm() < 1e-14);
      }
      // Gradients of a partition of unity vanish.
      const Eigen::MatrixXd Gx = cb.grad_x * cb.C.transpose();
      REQUIRE(Gx.rowwise().sum().cwiseAbs().maxCoeff() < 1e-12);
    }
  }
}

TEST_CASE("Uniform meshes store few distinct extraction matrices", "[geometry]") {
  TensorSpaceOptions o;
  o.degree = {3, 3};
  o.elements_per_span = {64, 64};
  const auto d = build_tensor_discretization(rectangle_patch(0, 0, 1, 1), o);
  REQUIRE(d.mesh.num_cells() == 64 * 64);
  REQUIRE(d.mesh.num_functions() == 67 * 67);  // (N + p)^2
  // First and last p elements differ, interior ones are alike: (2p+1)^2 products at most.
  REQUIRE(d.mesh.num_distinct_extractions() <= 49);
}

TEST_CASE("Extra knots refine the space and leave the geometry unchanged", "[geometry]") {
  TensorSpaceOptions o;
  o.degree = {3, 3};
  o.elements_per_span = {2, 2};
  o.continuity = {1, 2};
  o.extra_knots = {std::vector<double>{0.1, 0.2, 0.2, 0.5}, std::vector<double>{0.9}};
  const auto d = build_tensor_discretization(quarter_annulus_patch(1, 2), o);
  // n = (p + 1) + (p - r) * (number of distinct interior knots).
  // u: 0.5 (uniform) plus 0.1 and 0.2 (the repeated 0.2 counts once): 3 knots, p - r = 2.
  REQUIRE(d.space_u.num_functions() == (3 + 1) + (3 - 1) * 3);
  // v: 0.5 plus 0.9: 2 knots, p - r = 1.
  REQUIRE(d.space_v.num_functions() == (3 + 1) + (3 - 2) * 2);
  PatchGeometryMap g(d.mesh, d.patch, grid_of(d));
  REQUIRE(std::abs(area(d, g) - 0.75 * std::numbers::pi) < 1e-13);
  o.extra_knots = {std::vector<double>{1.5}, {}};
  REQUIRE_THROWS_WITH(build_tensor_discretization(quarter_annulus_patch(1, 2), o), Catch::Contains("not inside"));
}

TEST_CASE("Impossible spaces are refused with a reason", "[geometry]") {
  TensorSpaceOptions o;
  o.degree = {1, 1};
  REQUIRE_THROWS_WITH(build_tensor_discretization(quarter_annulus_patch(1, 2), o),
                      Catch::Contains("rational = false"));
  o.rational = false;
  REQUIRE_NOTHROW(build_tensor_discretization(quarter_annulus_patch(1, 2), o));
  o.degree = {3, 3};
  o.continuity = {3, 2};
  REQUIRE_THROWS_WITH(build_tensor_discretization(quarter_annulus_patch(1, 2), o), Catch::Contains("continuity"));
}

TEST_CASE("The tensor map at quadrature points (the patch as given, by direction) equals its Bezier route", "[geometry]") {
  // Two routes to the same map: evaluate_at_rule sums the original patch's B-splines one
  // direction at a time; evaluate() goes through the Bezier extraction of the geometry refined
  // onto the space. Rational (annulus) and with an interior C0 knot (L-shape).
  for (const NurbsPatch& patch : {quarter_annulus_patch(1, 2), lshape_patch()})
    for (int p : {2, 4}) {
      TensorSpaceOptions o;
      o.degree = {p, p};
      o.elements_per_span = {3, 2};
      const TensorDiscretization disc = build_tensor_discretization(patch, o);
      const PatchGeometryMap g(disc.mesh, disc.patch, grid_of(disc));
      const BernsteinTable& t = bernstein_table(1, 1, 4, 5);
      for (int c = 0; c < disc.mesh.num_cells(); ++c) {
        GeometryAtPoints fast, bezier;
        g.evaluate_at_rule(c, 4, 5, fast);
        g.evaluate(c, t.point_u, t.point_v, bezier);
        const double scale = bezier.jacobian.cwiseAbs().maxCoeff() + bezier.x.cwiseAbs().maxCoeff();
        REQUIRE((fast.x - bezier.x).cwiseAbs().maxCoeff() <= 1e-14 * scale);
        REQUIRE((fast.jacobian - bezier.jacobian).cwiseAbs().maxCoeff() <= 1e-13 * scale);
      }
    }
}

// A rank's part (RowShare) against the whole space, by brute force: the owned cells of all
// ranks tile the mesh, the owned functions tile [0, N), each part's cells are the whole mesh's
// (same functions after the offset, same extraction, weights and geometry), and every cell on
// which an owned function lives is in the part.
TEST_CASE("Row parts of a tensor space tile it and hold every cell their functions need", "[geometry][parts]") {
  struct Setting {
    std::array<int, 2> degree, elements, continuity;
    std::vector<double> knots_v;
  };
  const std::vector<Setting> settings{{{2, 2}, {3, 8}, {-1, -1}, {}},
                                      {{3, 2}, {2, 7}, {2, 0}, {0.3141}},
                                      {{2, 4}, {3, 5}, {1, 1}, {0.05, 0.71}},
                                      {{2, 3}, {2, 4}, {-1, -1}, {}}};
  for (const Setting& s : settings) {
    TensorSpaceOptions o;
    o.degree = s.degree;
    o.elements_per_span = s.elements;
    o.continuity = s.continuity;
    o.extra_knots[1] = s.knots_v;
    const TensorDiscretization whole = build_tensor_discretization(quarter_annulus_patch(1, 2), o);
    const PatchGeometryMap whole_map(whole.mesh, whole.patch, grid_of(whole));
    const int n = whole.mesh.num_functions(), rows = whole.elements_v, eu = whole.elements_u;
    // Cells of every function in the whole mesh.
    std::vector<std::vector<int>> cells_of(n);
    for (int c = 0; c < whole.mesh.num_cells(); ++c)
      for (int f : whole.mesh.functions(c)) cells_of[f].push_back(c);
    for (int ranks = 2; ranks <= std::min(rows, 5); ++ranks) {
      INFO("degree " << s.degree[0] << "x" << s.degree[1] << ", " << rows << " rows, " << ranks << " ranks");
      std::vector<int> cell_owner(whole.mesh.num_cells(), -1), function_owner(n, -1);
      for (int r = 0; r < ranks; ++r) {
        const TensorDiscretization part = build_tensor_discretization(quarter_annulus_patch(1, 2), o, RowShare{r, ranks});
        REQUIRE(part.part);
        const MeshPart& mp = *part.part;
        REQUIRE(mp.global_functions == n);
        REQUIRE(mp.global_cells == whole.mesh.num_cells());
        const PatchGeometryMap map(part.mesh, part.patch, grid_of(part));
        std::vector<int> whole_cell_of(part.mesh.num_cells());
        for (int c = 0; c < part.mesh.num_cells(); ++c) {
          const BezierCell& cell = part.mesh.cell(c);
          const int w = cell.index_u + eu * cell.index_v;
          whole_cell_of[c] = w;
          const auto mine = part.mesh.functions(c), theirs = whole.mesh.functions(w);
          REQUIRE(mine.size() == theirs.size());
          for (size_t a = 0; a < mine.size(); ++a) REQUIRE(mine[a] + mp.function_offset == theirs[a]);
          REQUIRE((part.mesh.extraction(c) - whole.mesh.extraction(w)).cwiseAbs().maxCoeff() == 0);
          REQUIRE(cell.boundary == whole.mesh.cell(w).boundary);
          for (size_t a = 0; a < mine.size(); ++a)
            REQUIRE(part.mesh.weights()[mine[a]] == whole.mesh.weights()[theirs[a]]);
          const BezierGeometryCell g = map.bezier_cell(c), h = whole_map.bezier_cell(w);
          REQUIRE((g.points - h.points).cwiseAbs().maxCoeff() == 0);
          GeometryAtPoints at, at_whole;
          map.evaluate_at_rule(c, 3, 3, at);
          whole_map.evaluate_at_rule(w, 3, 3, at_whole);
          REQUIRE((at.x - at_whole.x).cwiseAbs().maxCoeff() == 0);
          REQUIRE((at.jacobian - at_whole.jacobian).cwiseAbs().maxCoeff() == 0);
          if (c >= mp.owned.first && c < mp.owned.last) {
            REQUIRE(cell_owner[w] == -1);
            cell_owner[w] = r;
          }
        }
        std::sort(whole_cell_of.begin(), whole_cell_of.end());
        for (int f = mp.first_owned_function; f < mp.last_owned_function; ++f) {
          REQUIRE(function_owner[f] == -1);
          function_owner[f] = r;
          for (int c : cells_of[f]) REQUIRE(std::binary_search(whole_cell_of.begin(), whole_cell_of.end(), c));
        }
        // The rows: ceil(rows / ranks) of its own at most, and the q rows of the halo at most.
        REQUIRE(part.mesh.num_cells() <= ((rows + ranks - 1) / ranks + s.degree[1]) * eu);
      }
      REQUIRE(std::count(cell_owner.begin(), cell_owner.end(), -1) == 0);
      REQUIRE(std::count(function_owner.begin(), function_owner.end(), -1) == 0);
    }
    REQUIRE_THROWS_AS(build_tensor_discretization(quarter_annulus_patch(1, 2), o, RowShare{0, rows + 1}),
                      std::invalid_argument);
  }
}
