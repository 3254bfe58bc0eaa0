#include "basis/g1/g1_refine.hpp"

#include <stdexcept>

namespace knotwork {

namespace {

// Coefficients of p(u0 + u/2) from those of p (powers of u).
template <class Scalar, class Shift>
std::vector<Scalar> compose_half(const std::vector<Scalar>& p, const Shift& u0) {
  std::vector<Scalar> out(p.size(), Scalar(0));
  // Horner in the polynomial ring: q <- q * (u0 + u/2) + p_i (q has degree < deg p when
  // multiplied, so the product fits).
  for (size_t i = p.size(); i-- > 0;) {
    std::vector<Scalar> next(p.size(), Scalar(0));
    for (size_t j = 0; j + 1 < p.size(); ++j) {
      next[j] += out[j] * u0;
      next[j + 1] += out[j] / 2;
    }
    next[0] += p[i];
    out = std::move(next);
  }
  return out;
}

EdgeGluing restrict_edge(const EdgeGluing& g, int half) {
  return {restrict_to_half(g.a, half), restrict_to_half(g.b, half), restrict_to_half(g.c, half)};
}

EdgeGluing parametric_gluing() {
  return {PiecewisePolynomial::constant(0), PiecewisePolynomial::constant(-1), PiecewisePolynomial::constant(1)};
}

G1Refinement subdivide(const G1Refinement& coarse) {
  const QuadMesh& m = coarse.mesh;
  const int V = m.num_vertices(), E = m.num_edges();
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < V; ++v) points.push_back(m.vertex(v));
  for (int e = 0; e < E; ++e) points.push_back(0.5 * (m.vertex(m.edge(e).v[0]) + m.vertex(m.edge(e).v[1])));
  for (int f = 0; f < m.num_faces(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : m.face(f)) c += 0.25 * m.vertex(v);
    points.push_back(c);
  }
  std::vector<std::array<int, 4>> faces;
  G1Refinement fine;
  for (int f = 0; f < m.num_faces(); ++f) {
    const auto& v = m.face(f);
    // The 3 x 3 nodes of the face, (i, j) along (s, t).
    int node[3][3];
    node[0][0] = v[0], node[2][0] = v[1], node[2][2] = v[2], node[0][2] = v[3];
    node[1][0] = V + m.face_edge(f, 0), node[2][1] = V + m.face_edge(f, 1);
    node[1][2] = V + m.face_edge(f, 2), node[0][1] = V + m.face_edge(f, 3);
    node[1][1] = V + E + f;
    const CoarseFaceSquare& o = coarse.origin[f];
    for (int ht = 0; ht < 2; ++ht)
      for (int hs = 0; hs < 2; ++hs) {
        faces.push_back({node[hs][ht], node[hs + 1][ht], node[hs + 1][ht + 1], node[hs][ht + 1]});
        fine.origin.push_back({o.face, o.s0 + hs * o.size / 2, o.t0 + ht * o.size / 2, o.size / 2});
      }
  }
  fine.mesh = QuadMesh::from_faces(std::move(points), std::move(faces), "subdivided mesh");
  fine.gluing.edges.resize(fine.mesh.num_edges());
  for (int e = 0; e < fine.mesh.num_edges(); ++e) {
    const auto& edge = fine.mesh.edge(e);
    if (edge.boundary()) continue;
    const int a = edge.v[0], b = edge.v[1];
    const int old_vertex = a < V ? a : (b < V ? b : -1);
    if (old_vertex < 0) {  // centre to midpoint: inside an old face
      fine.gluing.edges[e] = parametric_gluing();
      continue;
    }
    const int old_edge = (a < V ? b : a) - V;
    const auto& oe = m.edge(old_edge);
    const int half = old_vertex == oe.v[0] ? 0 : 1;
    const EdgeGluing g = restrict_edge(*coarse.gluing.edges[old_edge], half);
    // Restricted data are for the old orientation: v[0] -> midpoint, or midpoint -> v[1].
    const bool same = half == 0 ? a == old_vertex : b == old_vertex;
    fine.gluing.edges[e] = same ? g : reversed(g);
  }
  return fine;
}

}  // namespace

PiecewisePolynomial restrict_to_half(const PiecewisePolynomial& p, int half) {
  if (p.exact) {
    const auto q = compose_half((*p.exact)[half], half == 0 ? mpq_class(0) : mpq_class(1, 2));
    return PiecewisePolynomial::from_exact({q, q});
  }
  if (p.algebraic) {
    const auto q = compose_half((*p.algebraic)[half], half == 0 ? mpq_class(0) : mpq_class(1, 2));
    return PiecewisePolynomial::from_algebraic({q, q});
  }
  const auto q = compose_half(p.pieces[half], 0.5 * half);
  return PiecewisePolynomial::from_double({q, q});
}

G1Refinement refine_g1(const QuadMesh& mesh, const GluingData& gluing, int levels) {
  if (levels < 0) throw std::invalid_argument("refine_g1: negative number of levels");
  if (static_cast<int>(gluing.edges.size()) != mesh.num_edges())
    throw std::invalid_argument("refine_g1: gluing data for " + std::to_string(gluing.edges.size()) +
                                " edges on a mesh with " + std::to_string(mesh.num_edges()));
  G1Refinement level{mesh, gluing, {}};
  for (int f = 0; f < mesh.num_faces(); ++f) level.origin.push_back({f, 0, 0, 1});
  for (int l = 0; l < levels; ++l) level = subdivide(level);
  return level;
}

}  // namespace knotwork
