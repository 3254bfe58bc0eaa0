#include <catch2/catch.hpp>
#include <Eigen/QR>
#include <cmath>
#include <random>
#include <set>

#include "basis/core/bspline_basis.hpp"
#include "quadrature/bernstein.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/knot_segments/collection_on_partition.hpp"
#include "basis/knot_segments/semi_regular_collection.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/core/geometry_map.hpp"
#include "solver/poisson_solver.hpp"
#include "tests/rounding_bounds.hpp"

using namespace knotwork;

namespace {

// Every property that does not depend on how the collection was built.
void check_properties(const SemiRegularCollection& c, bool with_formula) {
  const auto violations = c.violations();
  INFO((violations.empty() ? std::string("") : violations.front().reason));
  REQUIRE(violations.empty());
  const BezierMesh mesh = c.bezier_mesh();
  const int n = c.size();
  const int nb = (c.degree_x() + 1) * (c.degree_y() + 1);
  Eigen::MatrixXd global = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(mesh.num_cells()) * nb);
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    const Eigen::MatrixXd& C = mesh.extraction(cell);
    // Partition of unity: the Bernstein polynomials sum to 1, so the columns must.
    REQUIRE((C.colwise().sum().array() - 1.0).abs().maxCoeff() < 1e-13);
    REQUIRE(C.minCoeff() > -1e-14);  // non-negative
    const auto ids = mesh.functions(cell);
    for (size_t a = 0; a < ids.size(); ++a) global.block(ids[a], static_cast<Eigen::Index>(cell) * nb, 1, nb) = C.row(a);
  }
  // Linear independence: the functions' Bezier coefficients over all cells have full rank.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(global.transpose());
  qr.setThreshold(1e-10);
  REQUIRE(qr.rank() == n);
  if (with_formula) {
    const RectangularPartition part = c.partition();
    const int d = c.degree_x();
    const long brute = spline_space_dimension(part, d, d, d - 1, d - 1).dimension;
    REQUIRE(n == weller_dimension_formula(partition_topology(part), d));
    REQUIRE(n == brute);
  }
}

std::vector<double> random_breaks(std::mt19937& rng, int pieces) {
  std::vector<double> b{0};
  for (int i = 0; i < pieces; ++i) b.push_back(b.back() + (1 + rng() % 4) / 8.0);
  return b;
}

// A tensor-product collection of bi-degree d on random breakpoints, the y ones drawn first:
// the order gcc evaluated tensor_product(d, d, random_breaks(...), random_breaks(...)) when
// these tests were written. Argument order is unspecified (clang goes left to right), so it
// is spelled out here, and every compiler sees the same sequences. `pieces` 0: 2 to 4, drawn.
SemiRegularCollection random_tensor(std::mt19937& rng, int d, int x_pieces, int y_pieces) {
  auto draw = [&](int pieces) { return random_breaks(rng, pieces > 0 ? pieces : 2 + static_cast<int>(rng() % 3)); };
  const std::vector<double> ys = draw(y_pieces);
  const std::vector<double> xs = draw(x_pieces);
  return SemiRegularCollection::tensor_product(d, d, xs, ys);
}

// A random segment across the current knots: position halfway between two knots, ends on knots.
KnotInsertion random_segment(std::mt19937& rng, const SemiRegularCollection& c) {
  KnotInsertion s;
  s.vertical = rng() % 2;
  std::set<double> across, along;
  for (const auto& b : c.splines()) {
    across.insert((s.vertical ? b.x : b.y).begin(), (s.vertical ? b.x : b.y).end());
    along.insert((s.vertical ? b.y : b.x).begin(), (s.vertical ? b.y : b.x).end());
  }
  const std::vector<double> a(across.begin(), across.end()), l(along.begin(), along.end());
  const size_t i = rng() % (a.size() - 1);
  s.position = 0.5 * (a[i] + a[i + 1]);
  size_t f = rng() % (l.size() - 1), t = rng() % (l.size() - 1);
  if (f > t) std::swap(f, t);
  s.from = l[f];
  s.to = l[t + 1];
  return s;
}

}  // namespace

TEST_CASE("Tensor-product start: semi-regular, and the count is (n+d)^2", "[semi-regular]") {
  for (int d = 1; d <= 4; ++d) {
    const auto c = SemiRegularCollection::tensor_product(d, d, {0, 0.25, 0.5, 1}, {0, 0.5, 0.75, 1});
    REQUIRE(c.size() == (3 + d) * (3 + d));
    check_properties(c, true);
  }
}

TEST_CASE("Random refinement sequences keep a semi-regular basis of the full spline space", "[semi-regular]") {
  using E = SemiRegularCollection::Extension;
  // Every extension order: each must end in a checked semi-regular collection.
  const auto [extension, name] = GENERATE(std::make_pair(E::kGalloping, "galloping"), std::make_pair(E::kDirected, "directed"),
                                          std::make_pair(E::kMinimal, "minimal"));
  INFO("extension " << name);
  std::mt19937 rng(2024);
  int sequences = 0, insertions = 0, extended = 0, t_meshes = 0, with_segments = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int d = 1 + trial % 4;
    auto c = random_tensor(rng, d, 0, 0);
    c.set_extension(extension);
    const int steps = 1 + static_cast<int>(rng() % 4);
    for (int s = 0; s < steps; ++s) {
      const InsertionReport r = c.insert(random_segment(rng, c));
      extended += r.extended;
      ++insertions;
      INFO("trial " << trial << ", d = " << d << ", step " << s);
      check_properties(c, true);
      const PartitionTopology topo = partition_topology(c.partition());
      t_meshes += topo.t_nodes() > 0;
      with_segments += topo.count(PartitionTopology::KnotKind::kSegment) > 0;
    }
    ++sequences;
  }
  INFO(sequences << " sequences, " << insertions << " insertions, " << extended << " extended");
  REQUIRE(sequences == 200);
  // Not vacuous: most refinements leave tensor grids behind (T-nodes), some with knot
  // segments that end inside the domain at both ends.
  REQUIRE(t_meshes > insertions / 2);
  REQUIRE(with_segments > 10);
  WARN("semi-regular property test (" << name << " extension): " << sequences << " sequences, " << insertions << " insertions (" << extended
                                      << " extended), " << t_meshes << " T-meshes, " << with_segments
                                      << " with knot segments");
}

TEST_CASE("A T-mesh of a refined collection gets a collection back from its cells alone", "[semi-regular]") {
  // The construction sees only the cells; the random sequences show that such partitions
  // carry a semi-regular collection. It must find one of the same size (Prop. 4.2: both are
  // bases of the spline space over the partition).
  std::mt19937 rng(77);
  int reached = 0, t_meshes = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int d = 1 + trial % 4;
    auto c = random_tensor(rng, d, 0, 0);
    const int steps = 1 + static_cast<int>(rng() % 4);
    for (int s = 0; s < steps; ++s) c.insert(random_segment(rng, c));
    const RectangularPartition part = c.partition();
    t_meshes += partition_topology(part).t_nodes() > 0;
    const CollectionOnPartition built = collection_on_partition(part, d, d);
    INFO("trial " << trial << ", d = " << d << ", " << part.num_cells() << " cells, order " << built.order);
    REQUIRE(built.reached);
    reached += built.reached;
    REQUIRE(built.collection.size() == c.size());
    check_properties(built.collection, true);
  }
  REQUIRE(t_meshes > 100);
  WARN("collection on a given partition: " << reached << " of 200 T-meshes rebuilt (" << t_meshes << " with T-nodes)");
}

TEST_CASE("A copy refines like the original: the support index is rebuilt, not shared", "[semi-regular]") {
  // The insertions find B-splines through an R-tree of supports kept up to date by splits and
  // undone attempts; a copy builds its own. If either went stale, the two would differ.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int d = 2 + trial % 2;
    auto c = random_tensor(rng, d, 4, 4);
    for (int s = 0; s < 3; ++s) c.insert(random_segment(rng, c));
    SemiRegularCollection copy = c;
    const KnotInsertion next = random_segment(rng, c);
    const InsertionReport a = c.insert(next), b = copy.insert(next);
    INFO("trial " << trial);
    REQUIRE(a.inserted.from == b.inserted.from);
    REQUIRE(a.inserted.to == b.inserted.to);
    REQUIRE(c.splines() == copy.splines());
    // And a collection rebuilt from the B-splines alone (no index, no insertion history).
    const SemiRegularCollection fresh = SemiRegularCollection::from_splines(d, d, c.splines());
    REQUIRE(fresh.violations().empty());
  }
}

TEST_CASE("A short segment is extended until it refines, and the extension is reported", "[semi-regular]") {
  auto c = SemiRegularCollection::tensor_product(2, 2, {0, 1, 2, 3, 4}, {0, 1, 2, 3, 4});
  // x = 1.5 over one cell height cannot split any biquadratic (support 3 cells high).
  const InsertionReport r = c.insert({true, 1.5, 1, 2});
  REQUIRE(r.extended);
  REQUIRE(r.splits > 0);
  REQUIRE(r.inserted.to - r.inserted.from > 1);
  check_properties(c, true);
  REQUIRE_THROWS(c.insert({true, 5, 0, 1}));
  REQUIRE_THROWS(c.insert({true, 1.5, 2, 2}));
}

TEST_CASE("Poisson on a refined collection: patch test through the BezierMesh", "[semi-regular][poisson]") {
  auto c = SemiRegularCollection::tensor_product(2, 2, {0, 0.25, 0.5, 0.75, 1}, {0, 0.25, 0.5, 0.75, 1});
  c.insert({true, 0.375, 0, 0.75});
  c.insert({false, 0.375, 0.25, 1});
  const BezierMesh mesh = c.bezier_mesh();
  const AnalyticGeometryMap identity(mesh, [](double u, double v, double* x, double* J) {
    x[0] = u;
    x[1] = v;
    J[0] = 1; J[1] = 0; J[2] = 0; J[3] = 1;
  });
  PoissonProblem problem;
  problem.exact = differentiate_exact_solution(Expression::parse("x^2 - 3*x*y + 2*y^2 + x", "test"));
  problem.source = problem.exact->minus_laplacian;
  problem.boundary.assign(4, BoundaryCondition{});
  REQUIRE_REPRODUCED(rounding_test::solve_reproducing(mesh, identity, problem));
}

TEST_CASE("Collections that are not semi-regular are reported, naming the cell", "[semi-regular]") {
  // Drop one function of a tensor-product basis: the cells it covered lack a B-spline.
  auto c = SemiRegularCollection::tensor_product(1, 1, {0, 1, 2}, {0, 1, 2});
  REQUIRE(c.violations().empty());
  std::vector<LocalBSpline> splines = c.splines();
  splines.erase(splines.begin() + 4);  // the centre hat
  const auto v = SemiRegularCollection::from_splines(1, 1, splines).violations();
  REQUIRE(v.size() == 4);  // the four cells around the centre
  REQUIRE_THAT(v.front().reason, Catch::Contains("cell [0,1]x[0,1]") && Catch::Contains("3 B-splines are alive, not 4"));
}

TEST_CASE("Refinement keeps the spaces nested: coarse functions are exact on the fine collection", "[semi-regular]") {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 40; ++trial) {
    const int d = 1 + trial % 4;
    auto coarse = random_tensor(rng, d, 3, 3);
    coarse.insert(random_segment(rng, coarse));
    auto fine = coarse;
    for (int s = 0; s < 2; ++s) fine.insert(random_segment(rng, fine));
    // Every coarse B-spline, restricted to every fine cell (its Bernstein coefficients
    // there), must be a combination of the fine B-splines: a least-squares fit over all
    // fine cells has zero residual.
    const BezierMesh fm = fine.bezier_mesh();
    const int nb = (d + 1) * (d + 1), nf = fine.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(fm.num_cells()) * nb, nf);
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(A.rows(), coarse.size());
    for (int cell = 0; cell < fm.num_cells(); ++cell) {
      const auto ids = fm.functions(cell);
      const Eigen::MatrixXd& C = fm.extraction(cell);
      for (size_t a = 0; a < ids.size(); ++a) A.block(static_cast<Eigen::Index>(cell) * nb, ids[a], nb, 1) = C.row(a).transpose();
      const BezierCell& bc = fm.cell(cell);
      for (int k = 0; k < coarse.size(); ++k) {
        const auto& b = coarse.splines()[k];
        if (!(b.x.front() <= bc.u0 && bc.u1 <= b.x.back() && b.y.front() <= bc.v0 && bc.v1 <= b.y.back())) continue;
        const Eigen::VectorXd bx = single_bspline_bernstein(b.x, bc.u0, bc.u1);
        const Eigen::VectorXd by = single_bspline_bernstein(b.y, bc.v0, bc.v1);
        for (int v = 0; v <= d; ++v)
          for (int u = 0; u <= d; ++u) B(static_cast<Eigen::Index>(cell) * nb + u + (d + 1) * v, k) = bx[u] * by[v];
      }
    }
    const Eigen::MatrixXd X = A.colPivHouseholderQr().solve(B);
    REQUIRE((A * X - B).cwiseAbs().maxCoeff() < 1e-12);
    REQUIRE(fine.size() >= coarse.size());
  }
}

TEST_CASE("Partitions of semi-regular collections satisfy Lemma 3.4 / Prop. 4.1, a short segment does not", "[semi-regular]") {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 60; ++trial) {
    const int d = 1 + trial % 4;
    auto c = random_tensor(rng, d, 3, 3);
    for (int s = 0; s < 3; ++s) {
      c.insert(random_segment(rng, c));
      const auto v = weller_hypotheses_violations(partition_topology(c.partition()), d);
      INFO((v.empty() ? std::string() : v.front()));
      REQUIRE(v.empty());
    }
  }
  // The 3 x 3 grid with a segment of 2 vertices inside the centre cell (d = 2).
  std::vector<RationalBox> cells;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      if (!(i == 1 && j == 1)) cells.push_back({i, j, i + 1, j + 1});
  cells.push_back({1, 1, mpq_class(3, 2), 2});
  cells.push_back({mpq_class(3, 2), 1, 2, 2});
  const auto v = weller_hypotheses_violations(partition_topology(RectangularPartition(cells)), 2);
  REQUIRE(!v.empty());
  REQUIRE_THAT(v.front(), Catch::Contains("knot segment with 2 vertices"));
}

TEST_CASE("Weller's multiple de Boor evaluation agrees with Bezier extraction", "[semi-regular]") {
  std::mt19937 rng(99);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> unit(0, 1);
  int points = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int d = 1 + trial % 4;
    auto c = random_tensor(rng, d, 3, 2 + trial % 2);
    for (int s = 0; s < 1 + trial % 3; ++s) c.insert(random_segment(rng, c));
    std::vector<double> coef(c.size());
    for (double& v : coef) v = g(rng);
    const BezierMesh mesh = c.bezier_mesh();
    for (int cell = 0; cell < mesh.num_cells(); ++cell) {
      const BezierCell& bc = mesh.cell(cell);
      const auto ids = mesh.functions(cell);
      Eigen::VectorXd local(ids.size());
      for (size_t a = 0; a < ids.size(); ++a) local[a] = coef[ids[a]];
      const Eigen::VectorXd beta = mesh.extraction(cell).transpose() * local;
      for (int k = 0; k < 3; ++k) {
        // Corners are included: on a knot the point belongs to the cell above / right.
        const double s = k == 0 ? 0.0 : unit(rng), t = k == 0 ? 0.0 : unit(rng);
        std::vector<double> bu(d + 1), du(d + 1), bv(d + 1), dv(d + 1);
        bernstein_values_and_derivatives(d, s, bu.data(), du.data());
        bernstein_values_and_derivatives(d, t, bv.data(), dv.data());
        double bezier = 0;
        for (int v = 0; v <= d; ++v)
          for (int u = 0; u <= d; ++u) bezier += beta[u + (d + 1) * v] * bu[u] * bv[v];
        const double x = bc.u0 + s * (bc.u1 - bc.u0), y = bc.v0 + t * (bc.v1 - bc.v0);
        REQUIRE(std::abs(c.evaluate(coef, x, y) - bezier) < 1e-13 * (1 + std::abs(bezier)));
        ++points;
      }
    }
  }
  REQUIRE(points > 1000);
}

TEST_CASE("Conversion to a classical tensor-product B-spline keeps every value", "[semi-regular]") {
  std::mt19937 rng(123);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 40; ++trial) {
    const int d = 1 + trial % 4;
    auto c = random_tensor(rng, d, 3, 3);
    for (int s = 0; s < 2; ++s) c.insert(random_segment(rng, c));
    std::vector<double> coef(c.size());
    for (double& v : coef) v = g(rng);
    const TensorProductSpline t = c.to_tensor_product(coef);
    REQUIRE(t.basis_x.num_functions() * t.basis_y.num_functions() >= c.size());  // more functions, same spline
    const double X = t.basis_x.domain_end(), Y = t.basis_y.domain_end();
    for (int k = 0; k < 30; ++k) {
      const double x = unit(rng) * X, y = unit(rng) * Y;
      const double v = c.evaluate(coef, x, y);
      REQUIRE(std::abs(t(x, y) - v) < 1e-12 * (1 + std::abs(v)));
    }
  }
}

TEST_CASE("Knots of higher multiplicity and marked-cell refinement keep the properties", "[semi-regular]") {
  std::mt19937 rng(5150);
  for (int trial = 0; trial < 40; ++trial) {
    const int d = 2 + trial % 3;
    auto c = random_tensor(rng, d, 3, 3);
    const int before = c.size();
    KnotInsertion s = random_segment(rng, c);
    s.from = s.vertical ? 0 : 0;  // a full line of multiplicity m adds m functions per row
    const std::vector<double> ends = {c.splines().back().x.back(), c.splines().back().y.back()};
    s.to = s.vertical ? ends[1] : ends[0];
    s.multiplicity = 1 + trial % d;
    c.insert(s);
    const int rows = static_cast<int>(std::sqrt(double(before)) + 0.5);  // square tensor start: rows = columns
    REQUIRE(c.size() == before + s.multiplicity * rows);
    check_properties(c, false);
    const int cells = c.bezier_mesh().num_cells();
    c.refine_cells({0, cells - 1});
    check_properties(c, false);
    REQUIRE(c.bezier_mesh().num_cells() >= cells + 6);
  }
  auto c = SemiRegularCollection::tensor_product(2, 2, {0, 1, 2, 3}, {0, 1, 2, 3});
  REQUIRE_THROWS_WITH(c.insert({true, 1.5, 0, 3, 0}), Catch::Contains("multiplicity 0"));
  REQUIRE_THROWS_WITH(c.insert({true, 1.5, 0, 3, 4}), Catch::Contains("multiplicity 4"));
  c.insert({true, 1.5, 0, 3, 2});
  REQUIRE_THROWS_WITH(c.insert({true, 1.5, 1, 2, 1}), Catch::Contains("multiplicity 2"));
}
