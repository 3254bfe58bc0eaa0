// Refinement of G1 macro-patch spaces by quad-mesh subdivision with restricted gluing data:
// the restriction itself, the conditions at the new vertices, nestedness (coarse functions,
// re-expressed on the fine faces by interpolation written here, satisfy the fine conditions)
// and dimensions against the tensor-product count on grids.
#include <catch2/catch.hpp>

#include <Eigen/LU>

#include "basis/core/bspline_basis.hpp"
#include "basis/g1/g1_basis.hpp"
#include "basis/g1/g1_refine.hpp"
#include "tests/g1_test_meshes.hpp"

using namespace knotwork;
using namespace knotwork::test;

namespace {

// Values of a face's tensor B-spline function (coefficients g1_unknown order) at (s, t).
double face_value(const Eigen::VectorXd& x, int face, int k, int r, double s, double t) {
  const BSplineBasis1D b(k, g1_face_knots(k, r));
  const int ss = b.find_span(s), st = b.find_span(t);
  std::vector<double> ns(k + 1), nt(k + 1);
  b.evaluate(ss, s, ns.data());
  b.evaluate(st, t, nt.data());
  double v = 0;
  for (int i = 0; i <= k; ++i)
    for (int j = 0; j <= k; ++j) v += ns[i] * nt[j] * x(g1_unknown(face, ss - k + i, st - k + j, k, r));
  return v;
}

// The fine mesh's B-spline coefficients of a coarse function: per fine face, interpolation
// at the tensor Greville points (Schoenberg-Whitney: the collocation matrix is invertible).
Eigen::VectorXd to_fine(const Eigen::VectorXd& coarse, const G1Refinement& fine, int k, int r) {
  const int n = 2 * k - r + 1;
  const BSplineBasis1D b(k, g1_face_knots(k, r));
  std::vector<double> xi(n, 0.0);
  for (int i = 0; i < n; ++i) {
    for (int l = 1; l <= k; ++l) xi[i] += b.knots()[i + l];
    xi[i] /= k;
  }
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(n, n);  // N(point, function)
  for (int p = 0; p < n; ++p) {
    const int span = b.find_span(xi[p]);
    std::vector<double> v(k + 1);
    b.evaluate(span, xi[p], v.data());
    for (int i = 0; i <= k; ++i) N(p, span - k + i) = v[i];
  }
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(N);
  Eigen::VectorXd out(static_cast<Eigen::Index>(fine.mesh.num_faces()) * n * n);
  for (int f = 0; f < fine.mesh.num_faces(); ++f) {
    const auto& o = fine.origin[f];
    Eigen::MatrixXd values(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) values(i, j) = face_value(coarse, o.face, k, r, o.s0 + o.size * xi[i], o.t0 + o.size * xi[j]);
    const Eigen::MatrixXd c = lu.solve(Eigen::MatrixXd(lu.solve(values).transpose())).transpose();
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) out(g1_unknown(f, i, j, k, r)) = c(i, j);
  }
  return out;
}

double worst_row(const std::vector<std::vector<std::pair<long, double>>>& rows, const Eigen::VectorXd& x) {
  double worst = 0;
  for (const auto& row : rows) {
    double sum = 0, size = 0;
    for (const auto& [c, a] : row) {
      sum += a * x(c);
      size += std::abs(a);
    }
    worst = std::max(worst, std::abs(sum) / (size * x.cwiseAbs().maxCoeff()));
  }
  return worst;
}

}  // namespace

TEST_CASE("Restricting gluing data to half an edge composes with u0 + u/2, exactly", "[g1][refine]") {
  const auto p = PiecewisePolynomial::from_exact(
      {std::vector<mpq_class>{1, -3, mpq_class(5, 7)}, std::vector<mpq_class>{2, mpq_class(1, 3), -1}});
  for (int half = 0; half < 2; ++half) {
    const PiecewisePolynomial q = restrict_to_half(p, half);
    REQUIRE(q.exact);
    for (int i = 0; i <= 8; ++i) {
      mpq_class u(i, 8);
      u.canonicalize();  // GMP's operations expect canonical operands
      // Both pieces of the restriction are the same polynomial.
      REQUIRE((*q.exact)[0] == (*q.exact)[1]);
      // Evaluate piece `half` of p directly (exact_value would pick the piece by position).
      const auto& c = (*p.exact)[half];
      mpq_class x = mpq_class(half, 2) + u / 2;
      x.canonicalize();
      REQUIRE(q.exact_value(u) == c[0] + c[1] * x + c[2] * x * x);
    }
  }
}

// Condition 3.1 holds at every new vertex. Condition 3.2 (at crossing vertices) holds for the
// geometric data, which are C^1 at edge midpoints; the symmetric data are only C^0 there (the
// paper's Hermite blend), their a vanishes at the midpoint with different one-sided
// derivatives, and eqs. (6)-(7) fail at those new vertices: the restricted space is still the
// coarse one's refinement (next test), with the twist at the midpoint constrained as it
// already was in the coarse space.
TEST_CASE("Subdivided meshes: gluing conditions at the new vertices, origins tile the coarse faces",
          "[g1][refine]") {
  for (const QuadMesh& m : {three_quads(), fan(5, 0.2), cube(), torus(4, 3)}) {
    for (const bool symmetric : {true, false}) {
      const GluingData g = symmetric ? symmetric_gluing(m) : geometric_gluing(m);
      const G1Refinement fine = refine_g1(m, g, 2);
      REQUIRE(fine.mesh.num_faces() == 16 * m.num_faces());
      REQUIRE(fine.mesh.euler_characteristic() == m.euler_characteristic());
      REQUIRE(fine.gluing.exact() == g.exact());
      const auto violations = gluing_violations(fine.mesh, fine.gluing);
      const int old_edges = m.num_edges(), old_vertices = m.num_vertices();
      for (const auto& v : violations) {
        INFO(v);
        REQUIRE(symmetric);  // only the symmetric data, only Condition 3.2, ...
        REQUIRE(v.find("Condition 3.2") != std::string::npos);
        const int vertex = std::stoi(v.substr(7)) - 1;  // "vertex N ..." (1-based)
        REQUIRE(vertex >= old_vertices);                  // ... and only at old-edge midpoints
        REQUIRE(vertex < old_vertices + old_edges);
      }
      double area = 0;
      for (const auto& o : fine.origin) area += o.size * o.size;
      REQUIRE(area == Approx(m.num_faces()));
    }
  }
}

TEST_CASE("Subdivision nests the G1 spaces: coarse functions satisfy the fine conditions", "[g1][refine]") {
  struct Case {
    QuadMesh mesh;
    bool geometric;
    int k, r;
  };
  for (const Case& c : {Case{three_quads(), false, 4, 1}, Case{fan(5, 0.2), true, 4, 1}, Case{cube(), false, 4, 1},
                        Case{three_quads(), false, 5, 2}}) {
    const GluingData g = c.geometric ? geometric_gluing(c.mesh) : symmetric_gluing(c.mesh);
    const G1Basis coarse = g1_basis(c.mesh, g, c.k, c.r);
    const G1Refinement fine = refine_g1(c.mesh, g, 1);
    const auto rows = g1_condition_rows(fine.mesh, fine.gluing, c.k, c.r);
    double worst = 0;
    for (size_t j = 0; j < coarse.functions.size(); j += 3) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(coarse.unknowns());
      for (const auto& [u, v] : coarse.functions[j].coefficients) x(u) = v;
      worst = std::max(worst, worst_row(rows, to_fine(x, fine, c.k, c.r)));
    }
    INFO(c.mesh.num_faces() << " faces, k = " << c.k << ", r = " << c.r);
    REQUIRE(worst < 1e-12);
    // A function of the fine space that is not C1 in the coarse sense would fail the coarse
    // conditions; the dimension grows.
    REQUIRE(g1_space_dimension(fine.mesh, fine.gluing, c.k, c.r).dimension > coarse.space.dimension);
  }
}

TEST_CASE("A subdivided grid has the G1 space of the finer grid (tensor-product C1 count)", "[g1][refine]") {
  const QuadMesh m = grid(2);
  for (int levels = 1; levels <= 2; ++levels) {
    const G1Refinement fine = refine_g1(m, symmetric_gluing(m), levels);
    const int n = 2 << levels;
    for (const auto& [k, r] : {std::pair{3, 1}, std::pair{4, 2}}) {
      const long d = univariate_dimension(n, k, r);
      REQUIRE(g1_space_dimension(fine.mesh, fine.gluing, k, r).dimension == d * d);
    }
  }
}
