#include "families/g1/g1_discretization.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "basis/core/bezier_ops.hpp"
#include "families/g1/g1_case.hpp"
#include "quadrature/bernstein.hpp"
#include "families/g1/gluing_file.hpp"
#include "solver/error_norms.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

GluingData case_gluing(const CaseDescription& c, const QuadMesh& mesh) {
  const auto& g = g1_section(c);
  GluingData gluing;
  try {
    gluing = make_gluing(g.gluing, mesh, g.mesh_file);
  } catch (const InputError& e) {
    throw InputError(c.path + ": [space] gluing: " + e.what());
  }
  const auto violations = gluing_violations(mesh, gluing);
  if (!violations.empty())
    throw InputError(c.path + ": [space] gluing: " + violations.front() +
                     (violations.size() > 1 ? " (and " + std::to_string(violations.size() - 1) + " more)" : ""));
  return gluing;
}

// The target of the least-squares fit at face point (s, t): the bilinear face, projected
// onto the case's shape.
Eigen::Vector3d target_point(const G1Section& g, const QuadMesh& mesh, int f, double s, double t) {
  const auto& v = mesh.face(f);
  const Eigen::Vector3d p = (1 - s) * (1 - t) * mesh.vertex(v[0]) + s * (1 - t) * mesh.vertex(v[1]) +
                            s * t * mesh.vertex(v[2]) + (1 - s) * t * mesh.vertex(v[3]);
  const Eigen::Vector3d q = p - g.center;
  if (g.shape == "sphere") return g.center + g.radius * q.normalized();
  if (g.shape == "torus") {
    const Eigen::Vector3d ring = g.major_radius * Eigen::Vector3d(q.x(), q.y(), 0).normalized();
    return g.center + ring + g.minor_radius * (q - ring).normalized();
  }
  return p;
}

double shape_distance(const G1Section& g, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p - g.center;
  if (g.shape == "sphere") return std::abs(q.norm() - g.radius);
  if (g.shape == "torus") {
    const double rho = std::hypot(q.x(), q.y());
    return std::abs(std::hypot(rho - g.major_radius, q.z()) - g.minor_radius);
  }
  return 0;
}

// The coarse cell's Bernstein coefficients restricted to [s0, s1] x [t0, t1] of that cell.
Eigen::MatrixX3d restrict_cell(const Eigen::MatrixX3d& P, int k, double s0, double s1, double t0, double t1) {
  const Eigen::MatrixXd Su = subdivision_matrix(k, s0, s1), Sv = subdivision_matrix(k, t0, t1);
  Eigen::MatrixX3d out = Eigen::MatrixX3d::Zero(P.rows(), 3);
  for (int b = 0; b <= k; ++b)
    for (int a = 0; a <= k; ++a)
      for (int d = 0; d <= k; ++d)
        for (int c = 0; c <= k; ++c) out.row(a + (k + 1) * b) += Su(a, c) * Sv(b, d) * P.row(c + (k + 1) * d);
  return out;
}

// Extremes over the cells of det J = (x_u x x_v)_z (planar, signed) or |x_u x x_v| (surface)
// at the tabulated points (B, Bu, Bv: points x Bernstein polynomials).
struct RegularityExtremes {
  double smallest = INFINITY, largest = 0;
  int cell = 0;                   // where the smallest is
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};
RegularityExtremes regularity_extremes(const std::vector<Eigen::MatrixX3d>& cells, const Eigen::MatrixXd& B,
                                       const Eigen::MatrixXd& Bu, const Eigen::MatrixXd& Bv, bool surface) {
  RegularityExtremes r;
  for (size_t c = 0; c < cells.size(); ++c) {
    const Eigen::MatrixX3d x = B * cells[c], xu = Bu * cells[c], xv = Bv * cells[c];
    for (Eigen::Index q = 0; q < x.rows(); ++q) {
      const Eigen::Vector3d n = xu.row(q).cross(xv.row(q));
      const double measure = surface ? n.norm() : n.z();
      r.largest = std::max(r.largest, std::abs(measure));
      if (measure < r.smallest) {
        r.smallest = measure;
        r.cell = static_cast<int>(c);
        r.point = x.row(q).transpose();
      }
    }
  }
  return r;
}

}  // namespace

std::vector<CellInterface> g1_cell_interfaces(const QuadMesh& mesh) {
  // Corner frames: origin and direction of each face corner's outgoing edge in (s, t), the
  // same as the corner's cell side (bottom, right, top, left).
  static constexpr double kOrigin[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  static constexpr double kDir[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  // Cell of face f holding the face point (s, t) (4 cells, 4 f + 2 ht + hs), and the cell's
  // reference coordinate along `side` at that point.
  auto locate = [](int f, int side, double s, double t, int half_s, int half_t) {
    const int cell = 4 * f + 2 * half_t + half_s;
    const double along = side == kSideBottom || side == kSideTop ? 2 * s - half_s : 2 * t - half_t;
    return std::pair{cell, along};
  };
  std::vector<CellInterface> out;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    // Inside the face: the 2 x 2 cells of the 4-split.
    for (int h = 0; h < 2; ++h) {
      out.push_back({4 * f + 2 * h, kSideRight, 0, 1, 4 * f + 2 * h + 1, kSideLeft, 0, 1});
      out.push_back({4 * f + h, kSideTop, 0, 1, 4 * f + 2 + h, kSideBottom, 0, 1});
    }
  }
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    // Face 0 runs v0 -> v1 from corner[0]; face 1 runs v1 -> v0 from corner[1]. Each half of
    // the edge is a side of one cell in each face.
    const int c0 = E.corner[0], c1 = E.corner[1];
    for (int half = 0; half < 2; ++half) {
      const double w0 = 0.5 * half, w1 = 0.5 * half + 0.5, mid = 0.5 * (w0 + w1);
      auto point = [&](int c, double w) {
        return std::pair{kOrigin[c][0] + w * kDir[c][0], kOrigin[c][1] + w * kDir[c][1]};
      };
      const auto [sm0, tm0] = point(c0, mid);
      const auto [sm1, tm1] = point(c1, 1 - mid);
      const int hs0 = sm0 < 0.5 ? 0 : 1, ht0 = tm0 < 0.5 ? 0 : 1, hs1 = sm1 < 0.5 ? 0 : 1, ht1 = tm1 < 0.5 ? 0 : 1;
      const auto [s00, t00] = point(c0, w0);
      const auto [s01, t01] = point(c0, w1);
      const auto [s10, t10] = point(c1, 1 - w0);
      const auto [s11, t11] = point(c1, 1 - w1);
      const auto a_from = locate(E.face[0], c0, s00, t00, hs0, ht0), a_to = locate(E.face[0], c0, s01, t01, hs0, ht0);
      const auto b_from = locate(E.face[1], c1, s10, t10, hs1, ht1), b_to = locate(E.face[1], c1, s11, t11, hs1, ht1);
      out.push_back({a_from.first, static_cast<CellSide>(c0), a_from.second, a_to.second, b_from.first,
                     static_cast<CellSide>(c1), b_from.second, b_to.second});
    }
  }
  return out;
}

G1Discretization discretize_g1(const CaseDescription& c, int extra_levels,
                               const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  const auto& g = g1_section(c);
  G1Discretization d;
  try {
    d.coarse = g.coarse ? *g.coarse : QuadMesh::read_obj(g.mesh_file);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.path + ": [space] mesh: " + e.what());
  }
  d.coarse_gluing = case_gluing(c, d.coarse);
  const int k = g.degree, r = g.split_smoothness;
  for (int e : g1_inseparable_edges(d.coarse, d.coarse_gluing, k, r)) {
    const auto& E = d.coarse.edge(e);
    throw InputError(c.path + ": [space] degree: k = " + std::to_string(k) + " is below the separability of edge " +
                     std::to_string(E.v[0] + 1) + "-" + std::to_string(E.v[1] + 1) + " of " + g.mesh_file +
                     " for these gluing data (Definition 4.11: the Taylor data at its two ends are coupled, the "
                     "hypothesis of Theorem 7.1); raise the degree or lower split_smoothness" +
                     (g.gluing == "analysis_suitable" ? std::string(" (analysis_suitable data need k >= 4, and "
                                                                    "split_smoothness <= 2 at k = 4)")
                                                      : std::string()));
  }
  say("fitting the G1 geometry");
  const G1Basis coarse_basis = g1_basis(d.coarse, d.coarse_gluing, k, r);
  const Eigen::MatrixX3d fit = g1_fit(
      d.coarse, coarse_basis, [&](int f, double s, double t) { return target_point(g, d.coarse, f, s, t); },
      &d.fit_deviation);
  const BezierMesh coarse_mesh = g1_bezier_mesh(d.coarse, coarse_basis);
  const std::vector<Eigen::MatrixXd> coarse_cells = g1_cell_bernstein(coarse_mesh, fit);

  d.levels = g.refine + extra_levels;
  if (!g.c0) try {
      check_g1_construction_size(long(d.coarse.num_faces()) << (2 * d.levels), k, r);
    } catch (const std::length_error& e) {
      throw InputError(c.path + ": [space] refine: " + e.what() + "; subdivide less, or lower the degree");
    }
  say("building the G1 space (" + std::to_string(d.levels) + " subdivisions)");
  d.level = refine_g1(d.coarse, d.coarse_gluing, d.levels);
  try {
    // The geometry is the G1 fit in both cases, so the C0 baseline solves on the same domain.
    d.basis = g.c0 ? c0_multipatch_basis(d.level.mesh, k, r) : g1_basis(d.level.mesh, d.level.gluing, k, r, false, say);
  } catch (const std::runtime_error& e) {
    throw InputError(c.path + ": [space]: " + e.what());
  }
  d.mesh = g1_bezier_mesh(d.level.mesh, d.basis);
  d.mesh.set_interfaces(g1_cell_interfaces(d.level.mesh));

  // Geometry per fine cell: the coarse cell it lies in, restricted.
  std::vector<Eigen::MatrixX3d> cells(d.mesh.num_cells());
  for (int cell = 0; cell < d.mesh.num_cells(); ++cell) {
    const BezierCell& bc = d.mesh.cell(cell);
    const CoarseFaceSquare& o = d.level.origin[bc.patch];
    const double s0 = o.s0 + o.size * bc.u0, s1 = o.s0 + o.size * bc.u1;
    const double t0 = o.t0 + o.size * bc.v0, t1 = o.t0 + o.size * bc.v1;
    const int hs = s0 + 1e-12 < 0.5 ? 0 : 1, ht = t0 + 1e-12 < 0.5 ? 0 : 1;
    const Eigen::MatrixX3d P = coarse_cells[4 * o.face + 2 * ht + hs];
    cells[cell] = restrict_cell(P, k, 2 * s0 - hs, 2 * s1 - hs, 2 * t0 - ht, 2 * t1 - ht);
  }

  // Regularity, reported and enforced: det J (signed) in the plane, |x_u x x_v| on surfaces,
  // at the Gauss points (enforced) and at the cell corners and side midpoints (reported).
  {
    std::vector<BezierGeometryCell> bezier(cells.size());
    for (size_t i = 0; i < cells.size(); ++i) {
      bezier[i].degree_u = bezier[i].degree_v = k;
      bezier[i].points = g.surface ? Eigen::MatrixXd(cells[i]) : Eigen::MatrixXd(cells[i].leftCols(2));
    }
    d.geometry = std::make_unique<BezierCellsGeometryMap>(std::move(bezier));
  }
  const BernsteinTable& gauss = bernstein_table(k, k, k + 1, k + 1);
  const RegularityExtremes at_gauss = regularity_extremes(cells, gauss.value, gauss.d_u, gauss.d_v, g.surface);
  Eigen::VectorXd nu(9), nv(9);
  nu << 0, 0.5, 1, 0, 0.5, 1, 0, 0.5, 1;
  nv << 0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1;
  Eigen::MatrixXd B, Bu, Bv;
  tensor_bernstein(k, k, nu, nv, B, Bu, Bv);
  const RegularityExtremes at_nodes = regularity_extremes(cells, B, Bu, Bv, g.surface);
  d.min_regularity = at_gauss.largest > 0 ? at_gauss.smallest / at_gauss.largest : 0;
  d.min_regularity_nodes = at_gauss.largest > 0 ? at_nodes.smallest / at_gauss.largest : 0;
  d.worst_face = d.level.origin[d.mesh.cell(at_gauss.cell).patch].face;
  d.singular_point = at_nodes.point;
  if (g.surface) {
    for (const auto& cell : cells) {
      const Eigen::MatrixX3d x = gauss.value * cell;
      for (Eigen::Index q = 0; q < x.rows(); ++q)
        d.shape_distance = std::max(d.shape_distance, shape_distance(g, x.row(q).transpose()));
    }
  } else {
    // Straight boundary edges: distance of boundary control points from the chord.
    for (int cell = 0; cell < d.mesh.num_cells(); ++cell)
      for (int side = 0; side < 4; ++side) {
        if (d.mesh.cell(cell).boundary[side] < 0) continue;
        std::vector<Eigen::Vector2d> pts;
        for (int i = 0; i <= k; ++i) {
          const int a = side == kSideBottom ? i : side == kSideRight ? k : side == kSideTop ? k - i : 0;
          const int b = side == kSideBottom ? 0 : side == kSideRight ? i : side == kSideTop ? k : k - i;
          pts.push_back(cells[cell].row(a + (k + 1) * b).head<2>().transpose());
        }
        const Eigen::Vector2d dir = (pts.back() - pts.front()).normalized();
        for (const auto& p : pts) {
          const Eigen::Vector2d w = p - pts.front();
          d.boundary_deviation = std::max(d.boundary_deviation, std::abs(w.x() * dir.y() - w.y() * dir.x()));
        }
      }
  }
  if (!(d.min_regularity > 1e-8))
    throw InputError(c.path + ": [geometry]: the G1 geometry fitted to " + g.mesh_file + " is not regular at face " +
                     std::to_string(d.worst_face + 1) + " (" + (g.surface ? "smallest |x_u x x_v|" : "smallest det J") +
                     " relative to the largest: " + std::to_string(d.min_regularity) +
                     "); move the mesh's vertices so that its faces are convex, or choose other gluing data");
  return d;
}

double g1_gradient_jump(const G1Discretization& d, const Eigen::VectorXd& coefficients, int samples) {
  // Corner frames: origin and direction along the side of each face corner (s, t).
  static constexpr double kOrigin[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  static constexpr double kDir[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const QuadMesh& m = d.level.mesh;
  auto gradient_at = [&](int face, double s, double t) -> Eigen::Vector3d {
    const int hs = s < 0.5 ? 0 : 1, ht = t < 0.5 ? 0 : 1;
    const int cell = 4 * face + 2 * ht + hs;
    Eigen::VectorXd u(1), v(1);
    u << std::clamp(2 * s - hs, 0.0, 1.0);
    v << std::clamp(2 * t - ht, 0.0, 1.0);
    const Eigen::MatrixXd e = evaluate_solution(d.mesh, *d.geometry, coefficients, cell, u, v);
    return {e(0, 1), e(0, 2), e.cols() > 3 ? e(0, 3) : 0.0};
  };
  double jump = 0, largest = 0;
  for (int e = 0; e < m.num_edges(); ++e) {
    const auto& E = m.edge(e);
    if (E.boundary()) continue;
    for (int i = 0; i <= 2 * samples; ++i) {
      const double w = (i + 0.5) / (2 * samples + 1);  // avoids the split point exactly
      // face[0] runs v0 -> v1 from its corner[0]; face[1] runs v1 -> v0 from corner[1].
      const int c0 = E.corner[0], c1 = E.corner[1];
      const Eigen::Vector3d g0 =
          gradient_at(E.face[0], kOrigin[c0][0] + w * kDir[c0][0], kOrigin[c0][1] + w * kDir[c0][1]);
      const Eigen::Vector3d g1 =
          gradient_at(E.face[1], kOrigin[c1][0] + (1 - w) * kDir[c1][0], kOrigin[c1][1] + (1 - w) * kDir[c1][1]);
      jump = std::max(jump, (g0 - g1).norm());
      largest = std::max({largest, g0.norm(), g1.norm()});
    }
  }
  return largest > 0 ? jump / largest : 0;
}

}  // namespace knotwork
