#include "basis/g1/g1_space.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <type_traits>
#include <tuple>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>

#include "basis/exact/sparse_rank.hpp"

namespace knotwork {

// ---- piecewise polynomials ----

PiecewisePolynomial PiecewisePolynomial::constant(const mpq_class& v) {
  return from_exact({std::vector<mpq_class>{v}, std::vector<mpq_class>{v}});
}

PiecewisePolynomial PiecewisePolynomial::from_exact(std::array<std::vector<mpq_class>, 2> pieces) {
  PiecewisePolynomial p;
  for (int h = 0; h < 2; ++h) {
    if (pieces[h].empty()) pieces[h].push_back(0);
    for (const auto& q : pieces[h]) p.pieces[h].push_back(q.get_d());
  }
  p.exact = std::move(pieces);
  return p;
}

PiecewisePolynomial PiecewisePolynomial::from_double(std::array<std::vector<double>, 2> pieces) {
  PiecewisePolynomial p;
  for (int h = 0; h < 2; ++h)
    if (pieces[h].empty()) pieces[h].push_back(0);
  p.pieces = std::move(pieces);
  return p;
}

namespace {
// The piece at u of the double coefficients, by Horner's rule in Real (double, or long double
// for the rows the floating-point local constructions refine their null vectors against).
template <class Real>
Real evaluate_pieces(const std::array<std::vector<double>, 2>& pieces, Real u) {
  const auto& c = pieces[u < Real(0.5) ? 0 : 1];
  Real v = 0;
  for (size_t i = c.size(); i-- > 0;) v = v * u + c[i];
  return v;
}
}  // namespace

double PiecewisePolynomial::operator()(double u) const { return evaluate_pieces(pieces, u); }

mpq_class PiecewisePolynomial::exact_value(const mpq_class& u) const {
  const auto& c = (*exact)[u < mpq_class(1, 2) ? 0 : 1];
  mpq_class v = 0;
  for (size_t i = c.size(); i-- > 0;) v = v * u + c[i];
  return v;
}

int PiecewisePolynomial::degree() const {
  return static_cast<int>(std::max(pieces[0].size(), pieces[1].size())) - 1;
}

std::string GluingData::skewed_fans_list() const {
  std::string list;
  for (size_t i = 0; i < skewed_fans.size() && i < 12; ++i) list += (i ? ", " : "") + std::to_string(skewed_fans[i] + 1);
  if (skewed_fans.size() > 12) list += ", ...";
  return list;
}

bool GluingData::exact() const {
  for (const auto& e : edges)
    if (e && (!e->a.exact || !e->b.exact || !e->c.exact)) return false;
  return true;
}

namespace {

// 2cos(pi p/q): exact where it is rational (p/q a multiple of 1/2 or 1/3 in [0, 1]).
std::optional<mpq_class> two_cos_pi_exact(long p, long q) {
  mpq_class x(p, q);
  x.canonicalize();
  if (x == 0) return mpq_class(2);
  if (x == mpq_class(1, 3)) return mpq_class(1);
  if (x == mpq_class(1, 2)) return mpq_class(0);
  if (x == mpq_class(2, 3)) return mpq_class(-1);
  if (x == 1) return mpq_class(-2);
  return std::nullopt;
}

// The angle of the symmetric gluing at vertex v as a fraction of pi: 2/n inside (n edges),
// 1/F on the boundary (F faces).
std::pair<long, long> symmetric_angle(const QuadMesh& mesh, int v) {
  const auto& ring = mesh.ring(v);
  if (ring.boundary) return {1, static_cast<long>(ring.faces.size())};
  return {2, static_cast<long>(mesh.valence(v))};
}

// B-spline values and first derivatives of U_k^r (knots 0^(k+1), (1/2)^(k-r), 1^(k+1)) at
// u in [0, 1] other than 1/2.
template <class Scalar>
void univariate(int k, int r, const Scalar& u, std::vector<Scalar>& value, std::vector<Scalar>& derivative) {
  std::vector<Scalar> T;
  for (int i = 0; i <= k; ++i) T.push_back(Scalar(0));
  for (int i = 0; i < k - r; ++i) T.push_back(Scalar(1) / 2);
  for (int i = 0; i <= k; ++i) T.push_back(Scalar(1));
  const int n = static_cast<int>(T.size()) - k - 1;
  std::vector<Scalar> N(T.size() - 1, Scalar(0));
  // Half-open spans, except that u = 1 (a face side) belongs to the last one.
  for (size_t i = 0; i + 1 < T.size(); ++i)
    N[i] = ((T[i] <= u && u < T[i + 1]) || (u == T.back() && T[i] < u && T[i + 1] == u)) ? Scalar(1) : Scalar(0);
  std::vector<Scalar> lower;
  for (int p = 1; p <= k; ++p) {
    lower = N;
    for (size_t i = 0; i + p + 1 < T.size(); ++i) {
      Scalar v(0);
      if (T[i + p] != T[i]) v += (u - T[i]) / (T[i + p] - T[i]) * lower[i];
      if (T[i + p + 1] != T[i + 1]) v += (T[i + p + 1] - u) / (T[i + p + 1] - T[i + 1]) * lower[i + 1];
      N[i] = v;
    }
  }
  value.assign(N.begin(), N.begin() + n);
  derivative.assign(n, Scalar(0));
  for (int i = 0; i < n; ++i) {  // from the degree k-1 values still in `lower`
    if (T[i + k] != T[i]) derivative[i] += Scalar(k) / (T[i + k] - T[i]) * lower[i];
    if (T[i + k + 1] != T[i + 1]) derivative[i] -= Scalar(k) / (T[i + k + 1] - T[i + 1]) * lower[i + 1];
  }
}

// Corner frames of a face (docs/MATH.md §2): (s, t) = origin + u * du + v * dv.
constexpr int kOrigin[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
constexpr int kDu[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
constexpr int kDv[4][2] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};

// A linear functional on one face's coefficients: value or derivative along (ds, dt) at a
// point of the corner frame.
template <class Scalar>
struct FaceFunctional {
  std::vector<std::pair<long, Scalar>> terms;
};

template <class Scalar>
FaceFunctional<Scalar> face_functional(int face, int corner, const Scalar& u, const Scalar& v, const int* direction,
                                       int k, int r) {
  const Scalar s = Scalar(kOrigin[corner][0]) + u * kDu[corner][0] + v * kDv[corner][0];
  const Scalar t = Scalar(kOrigin[corner][1]) + u * kDu[corner][1] + v * kDv[corner][1];
  std::vector<Scalar> local[4];
  const std::vector<Scalar>*Ns = &local[0], *dNs = &local[1], *Nt = &local[2], *dNt = &local[3];
  if constexpr (std::is_same_v<Scalar, mpq_class>) {
    // The conditions of every edge sample the same few points: exact B-spline values are
    // remembered per thread (a fifth of a G1 build was recomputing them).
    thread_local std::map<std::tuple<int, int, mpq_class>, std::pair<std::vector<mpq_class>, std::vector<mpq_class>>> seen;
    auto values = [&](const mpq_class& x, const std::vector<mpq_class>*& value, const std::vector<mpq_class>*& derivative) {
      auto [it, added] = seen.try_emplace(std::tuple{k, r, x});
      if (added) univariate(k, r, x, it->second.first, it->second.second);
      value = &it->second.first;
      derivative = &it->second.second;
    };
    values(s, Ns, dNs);
    values(t, Nt, dNt);
  } else {
    univariate(k, r, s, local[0], local[1]);
    univariate(k, r, t, local[2], local[3]);
  }
  // Only the few B-splines that do not vanish at the point (k + 1 per direction at most, and
  // on an edge one or two across it) take part: the products are formed for those alone.
  auto nonzero = [](const std::vector<Scalar>& x, const std::vector<Scalar>* y) {
    std::vector<int> out;
    for (int i = 0; i < static_cast<int>(x.size()); ++i)
      if (x[i] != 0 || (y && (*y)[i] != 0)) out.push_back(i);
    return out;
  };
  const std::vector<int> is = nonzero(*Ns, direction ? dNs : nullptr), js = nonzero(*Nt, direction ? dNt : nullptr);
  FaceFunctional<Scalar> out;
  for (int i : is)
    for (int j : js) {
      Scalar c = direction ? Scalar(Scalar(direction[0]) * (*dNs)[i] * (*Nt)[j] + Scalar(direction[1]) * (*Ns)[i] * (*dNt)[j])
                           : Scalar((*Ns)[i] * (*Nt)[j]);
      if (c != 0) out.terms.emplace_back(g1_unknown(face, i, j, k, r), c);
    }
  return out;
}

// face_functional on face 0, remembered per thread for exact points (every edge samples the
// same points in one of four frames), shifted to `face`: its unknowns are face 0's plus
// face * n^2.
template <class Scalar>
FaceFunctional<Scalar> shared_face_functional(int face, int corner, const Scalar& u, const Scalar& v,
                                              const int* direction, int k, int r) {
  if constexpr (!std::is_same_v<Scalar, mpq_class>) {
    return face_functional<Scalar>(face, corner, u, v, direction, k, r);
  } else {
    using Key = std::tuple<int, int, int, int, int, int, mpq_class, mpq_class>;
    thread_local std::map<Key, FaceFunctional<mpq_class>> seen;
    const Key key{k, r, corner, direction != nullptr, direction ? direction[0] : 0, direction ? direction[1] : 0, u, v};
    auto [it, added] = seen.try_emplace(key);
    if (added) it->second = face_functional<mpq_class>(0, corner, u, v, direction, k, r);
    const long offset = g1_unknown(face, 0, 0, k, r);
    FaceFunctional<mpq_class> out = it->second;
    for (auto& term : out.terms) term.first += offset;
    return out;
  }
}

template <class Scalar>
Scalar gluing_value(const PiecewisePolynomial& p, const Scalar& u);
template <>
double gluing_value(const PiecewisePolynomial& p, const double& u) { return p(u); }
template <>
mpq_class gluing_value(const PiecewisePolynomial& p, const mpq_class& u) { return p.exact_value(u); }
template <>
long double gluing_value(const PiecewisePolynomial& p, const long double& u) { return evaluate_pieces(p.pieces, u); }

// The points where an edge's conditions are sampled: on each half of the edge, as many as make
// them polynomial identities there (the products c dv f1 etc. have degree k + deg data).
template <class Scalar>
std::vector<Scalar> condition_points(const EdgeGluing& g, int k) {
  const int points = k + std::max({g.a.degree(), g.b.degree(), g.c.degree(), 0}) + 1;
  std::vector<Scalar> u;
  for (int half = 0; half < 2; ++half)
    for (int q = 0; q < points; ++q) u.push_back(Scalar(half) / 2 + Scalar(q + 1) / (2 * (points + 1)));
  return u;
}

// The G1 conditions (2) and (3) across every interior edge, at enough points of each half
// of the edge to make them polynomial identities there.
template <class Scalar>
std::vector<std::vector<std::pair<long, Scalar>>> g1_conditions(const QuadMesh& mesh, const GluingData& gluing, int k,
                                                                int r, int only_edge = -1) {
  std::vector<std::vector<std::pair<long, Scalar>>> rows;
  const int first = only_edge >= 0 ? only_edge : 0, last = only_edge >= 0 ? only_edge + 1 : mesh.num_edges();
  for (int e = first; e < last; ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    const EdgeGluing& g = *gluing.edges[e];
    const int f1 = E.face[0], c1 = E.corner[0];
    const int f0 = E.face[1], c0 = (E.corner[1] + 1) % 4;  // face[1]'s corner at v[0]
    for (const Scalar& u : condition_points<Scalar>(g, k)) {
      const Scalar zero(0);
      // (2): f1(u, 0) - f0(0, u)
      const auto v1 = shared_face_functional<Scalar>(f1, c1, u, zero, nullptr, k, r);
      const auto v0 = shared_face_functional<Scalar>(f0, c0, zero, u, nullptr, k, r);
      std::vector<std::pair<long, Scalar>> row;
      for (const auto& [col, c] : v1.terms) row.emplace_back(col, c);
      for (const auto& [col, c] : v0.terms) row.emplace_back(col, -c);
      rows.push_back(std::move(row));
      // (3): c dv f1(u, 0) - b du f0(0, u) - a dv f0(0, u)
      const Scalar a = gluing_value(g.a, u), b = gluing_value(g.b, u), c = gluing_value(g.c, u);
      const auto d1 = shared_face_functional<Scalar>(f1, c1, u, zero, kDv[c1], k, r);
      const auto du0 = shared_face_functional<Scalar>(f0, c0, zero, u, kDu[c0], k, r);
      const auto dv0 = shared_face_functional<Scalar>(f0, c0, zero, u, kDv[c0], k, r);
      row.clear();
      for (const auto& [col, x] : d1.terms) row.emplace_back(col, c * x);
      for (const auto& [col, x] : du0.terms) row.emplace_back(col, -b * x);
      for (const auto& [col, x] : dv0.terms) row.emplace_back(col, -a * x);
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

}  // namespace

Eigen::MatrixXd dense_rows(const std::vector<std::vector<std::pair<long, double>>>& rows, long columns) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), columns);
  for (size_t i = 0; i < rows.size(); ++i)
    for (const auto& [c, x] : rows[i]) A(static_cast<Eigen::Index>(i), c) += x;
  return A;
}

long g1_corner_unknown(int face, int corner, int a, int b, int k, int r) {
  const int n = 2 * k - r + 1;
  const int i = kOrigin[corner][0] * (n - 1) + a * kDu[corner][0] + b * kDv[corner][0];
  const int j = kOrigin[corner][1] * (n - 1) + a * kDu[corner][1] + b * kDv[corner][1];
  return g1_unknown(face, i, j, k, r);
}

std::vector<double> g1_face_knots(int k, int r) {
  std::vector<double> knots(k + 1, 0.0);
  knots.insert(knots.end(), k - r, 0.5);
  knots.insert(knots.end(), k + 1, 1.0);
  return knots;
}

std::vector<std::vector<std::pair<long, double>>> g1_condition_rows(const QuadMesh& mesh, const GluingData& gluing,
                                                                    int k, int r, int edge) {
  return g1_conditions<double>(mesh, gluing, k, r, edge);
}
std::vector<std::vector<std::pair<long, long double>>> g1_condition_rows_long(const QuadMesh& mesh,
                                                                            const GluingData& gluing, int k, int r,
                                                                            int edge) {
  return g1_conditions<long double>(mesh, gluing, k, r, edge);
}
std::vector<std::vector<std::pair<long, mpq_class>>> g1_condition_rows_exact(const QuadMesh& mesh,
                                                                             const GluingData& gluing, int k, int r,
                                                                             int edge) {
  return g1_conditions<mpq_class>(mesh, gluing, k, r, edge);
}

GluingData symmetric_gluing(const QuadMesh& mesh, SymmetricBlend blend) {
  // a = A0 d0 - A1 d1, as coefficients of the two pieces, for each blend.
  auto pieces = [blend](const auto& A0, const auto& A1) {
    using T = std::decay_t<decltype(A0)>;
    if (blend == SymmetricBlend::kLinear)  // d0 = 1 - u, d1 = u on the whole edge
      return std::array<std::vector<T>, 2>{std::vector<T>{A0, T(-A0 - A1)}, std::vector<T>{A0, T(-A0 - A1)}};
    if (blend == SymmetricBlend::kC0)  // d0 = 1 - 4u^2 | 0, d1 = 0 | -3 + 8u - 4u^2 (C^0 at 1/2, the paper's)
      return std::array<std::vector<T>, 2>{std::vector<T>{A0, T(0), T(-4 * A0)},
                                           std::vector<T>{T(3 * A1), T(-8 * A1), T(4 * A1)}};
    // d0 = 1 - 2u^2 | 2(1-u)^2, d1 = 2u^2 | 1 - 2(1-u)^2 (C^1 at 1/2)
    return std::array<std::vector<T>, 2>{std::vector<T>{A0, T(0), T(-2 * A0 - 2 * A1)},
                                         std::vector<T>{T(2 * A0 + A1), T(-4 * A0 - 4 * A1), T(2 * A0 + 2 * A1)}};
  };
  GluingData g;
  g.edges.resize(mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    const auto [p0, q0] = symmetric_angle(mesh, E.v[0]);
    const auto [p1, q1] = symmetric_angle(mesh, E.v[1]);
    const auto x0 = two_cos_pi_exact(p0, q0), x1 = two_cos_pi_exact(p1, q1);
    EdgeGluing eg;
    if (x0 && x1)
      eg.a = PiecewisePolynomial::from_exact(pieces(mpq_class(*x0), mpq_class(*x1)));
    else  // exact still, as sums of cosines (their rank is taken modulo primes with roots of unity)
      eg.a = PiecewisePolynomial::from_algebraic(pieces(x0 ? CosineSum(*x0) : CosineSum::two_cos_pi(p0, q0),
                                                        x1 ? CosineSum(*x1) : CosineSum::two_cos_pi(p1, q1)));
    eg.b = PiecewisePolynomial::constant(-1);
    eg.c = PiecewisePolynomial::constant(1);
    g.edges[e] = std::move(eg);
  }
  return g;
}

namespace {

// p(1 - u) for a polynomial p given by coefficients in powers of u.
template <class Scalar>
std::vector<Scalar> reflect(const std::vector<Scalar>& p) {
  std::vector<Scalar> out(p.size(), Scalar(0));
  for (size_t i = 0; i < p.size(); ++i) {  // (1 - u)^i = sum_j C(i, j) (-u)^j
    long binom = 1;
    for (size_t j = 0; j <= i; ++j) {
      out[j] += (j % 2 ? -binom : binom) * p[i];
      binom = binom * static_cast<long>(i - j) / static_cast<long>(j + 1);
    }
  }
  return out;
}

PiecewisePolynomial reflected(const PiecewisePolynomial& p) {
  if (p.exact) return PiecewisePolynomial::from_exact({reflect((*p.exact)[1]), reflect((*p.exact)[0])});
  if (p.algebraic) return PiecewisePolynomial::from_algebraic({reflect((*p.algebraic)[1]), reflect((*p.algebraic)[0])});
  return PiecewisePolynomial::from_double({reflect(p.pieces[1]), reflect(p.pieces[0])});
}

}  // namespace

namespace {

// Eq. (8) of a planar fan of edge directions at edge `cur` between `prev` and `next` (counter-
// clockwise): with T = cur, X = next (dv f1), Y = prev (du f0), c X = b Y + a T holds for
// c = det(Y, T), b = det(X, T), a = det(Y, X) (three vectors of the plane): (a/c, b/c).
std::pair<mpq_class, mpq_class> fan_values(const std::array<mpq_class, 2>& prev, const std::array<mpq_class, 2>& cur,
                                           const std::array<mpq_class, 2>& next) {
  auto det = [](const std::array<mpq_class, 2>& x, const std::array<mpq_class, 2>& y) -> mpq_class {
    return x[0] * y[1] - x[1] * y[0];
  };
  const mpq_class d = det(prev, cur);
  return {det(prev, next) / d, det(next, cur) / d};
}

}  // namespace

EdgeGluing reversed(const EdgeGluing& g) { return {reflected(g.a), reflected(g.c), reflected(g.b)}; }

GluingData geometric_gluing(const QuadMesh& mesh, bool regular_fans_where_rational) {
  // Per (vertex, edge): the values a(0), b(0) of eq. (8) seen from that vertex. They are
  // ratios of 2x2 determinants, invariant under rotations and scalings of the tangent frame:
  // on a planar mesh the frame is the xy plane and they are rational in the coordinates,
  // computed exactly when the coordinates are short binary fractions (multiples of 2^-20,
  // as typed in a mesh file meant to be exact). Coordinates such as cos(2 pi / 5) rounded
  // to doubles are not: as exact rationals they make the space a perturbation of the
  // intended one, whose extra constraints are independent only at rounding level (an
  // ill-conditioned basis), so those data stay floating point and get a rank tolerance.
  bool exact = mesh.planar();
  for (int v = 0; v < mesh.num_vertices() && exact; ++v)
    for (int i = 0; i < 2; ++i) {
      const double scaled = std::ldexp(mesh.vertex(v)(i), 20);
      exact = exact && std::abs(scaled) < 0x1p40 && scaled == std::round(scaled);
    }
  std::vector<std::map<int, std::pair<mpq_class, mpq_class>>> at(mesh.num_vertices());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto& ring = mesh.ring(v);
    if (regular_fans_where_rational && !ring.boundary) {
      // The regular fan (eq. 8 for equal angles: a = 2cos(angle), b = -1) where that is
      // rational; boundary vertices keep the mesh's directions (a corner stays a corner).
      const auto [p, q] = symmetric_angle(mesh, v);
      if (const auto two_cos = two_cos_pi_exact(p, q)) {
        for (int e : ring.edges)
          if (!mesh.edge(e).boundary()) at[v][e] = {*two_cos, mpq_class(-1)};
        continue;
      }
    }
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (int f : ring.faces) {
      const auto& q = mesh.face(f);
      normal += (mesh.vertex(q[2]) - mesh.vertex(q[0])).cross(mesh.vertex(q[3]) - mesh.vertex(q[1]));
    }
    normal.normalize();
    std::vector<std::array<mpq_class, 2>> u;
    std::vector<double> length;
    Eigen::Vector3d e1, e2;
    for (size_t i = 0; i < ring.edges.size(); ++i) {
      const auto& E = mesh.edge(ring.edges[i]);
      const int w = E.v[0] == v ? E.v[1] : E.v[0];
      if (exact) {  // exact differences of the (binary) coordinates
        u.push_back({mpq_class(mesh.vertex(w).x()) - mpq_class(mesh.vertex(v).x()),
                     mpq_class(mesh.vertex(w).y()) - mpq_class(mesh.vertex(v).y())});
        length.push_back((mesh.vertex(w) - mesh.vertex(v)).norm());
        continue;
      }
      const Eigen::Vector3d d = mesh.vertex(w) - mesh.vertex(v);
      const Eigen::Vector3d t = d - d.dot(normal) * normal;
      if (i == 0) {
        e1 = t.normalized();
        e2 = normal.cross(e1);
      }
      u.push_back({mpq_class(t.dot(e1)), mpq_class(t.dot(e2))});
      length.push_back(t.norm());
    }
    const int n = static_cast<int>(u.size());
    for (int i = 0; i < n; ++i) {
      if (mesh.edge(ring.edges[i]).boundary()) continue;
      // The ring runs counter-clockwise: edge i is shared by faces[i] (f1, on its left: its
      // other edge at v is edge i + 1) and faces[i - 1] (f0: its other edge is edge i - 1).
      const int prev = ring.boundary ? i - 1 : (i + n - 1) % n, next = ring.boundary ? i + 1 : (i + 1) % n;
      const mpq_class d = u[prev][0] * u[i][1] - u[prev][1] * u[i][0];
      if (std::abs(d.get_d()) < 1e-12 * length[prev] * length[i])
        throw std::invalid_argument("vertex " + std::to_string(v + 1) +
                                    ": two consecutive edges are parallel in the tangent plane; the geometric gluing "
                                    "is undefined there (use symmetric)");
      at[v][ring.edges[i]] = fan_values(u[prev], u[i], u[next]);
    }
  }
  GluingData g;
  g.edges.resize(mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    const auto& [A0, B0] = at[E.v[0]].at(e);
    const auto& [A1p, B1p] = at[E.v[1]].at(e);
    const mpq_class A1 = A1p / B1p, B1 = 1 / B1p;  // the far end's values in this edge's frames
    // x0 d0 + x1 d1 with the C^1 Hermite functions d0 = 1 - 2u^2 | 2(1-u)^2 and
    // d1 = 2u^2 | 1 - 2(1-u)^2: d0 + d1 = 1, so equal end values stay constant along the
    // edge (a regular grid gets exactly the C1 data a = 0, b = -1).
    auto blend = [&](const mpq_class& x0, const mpq_class& x1) {
      std::array<std::vector<mpq_class>, 2> p{std::vector<mpq_class>{x0, 0, 2 * (x1 - x0)},
                                              std::vector<mpq_class>{2 * x0 - x1, 4 * (x1 - x0), 2 * (x0 - x1)}};
      if (exact) return PiecewisePolynomial::from_exact(std::move(p));
      std::array<std::vector<double>, 2> d;
      for (int h = 0; h < 2; ++h)
        for (const auto& x : p[h]) d[h].push_back(x.get_d());
      return PiecewisePolynomial::from_double(std::move(d));
    };
    g.edges[e] = EdgeGluing{blend(A0, A1), blend(B0, B1), PiecewisePolynomial::constant(1)};
  }
  return g;
}

namespace {

// A face's bilinear map in the frame of its corner c (docs/MATH.md §2: u along the side
// leaving the corner, v along the side arriving at it, reversed): the point and its partial
// derivatives at (u, v), as polynomials in u along one of the frame's axes. Coefficients
// (constant, linear, ...) of x and y.
struct CornerMap {
  std::array<mpq_class, 2> origin, du, dv, duv;  // G(u, v) = origin + u du + v dv + u v duv
};
CornerMap corner_map(const QuadMesh& mesh, int f, int c) {
  const auto& q = mesh.face(f);
  auto point = [&](int i, int d) { return mpq_class(mesh.vertex(q[(c + i) % 4])(d)); };
  CornerMap m;
  for (int d = 0; d < 2; ++d) {
    // Corners c, c+1, c+3 are the frame's (0,0), (1,0), (0,1); c+2 is (1,1).
    m.origin[d] = point(0, d);
    m.du[d] = point(1, d) - point(0, d);
    m.dv[d] = point(3, d) - point(0, d);
    m.duv[d] = point(2, d) - point(1, d) - point(3, d) + point(0, d);
  }
  return m;
}

// Products of linear polynomials (coefficients in powers of u).
std::vector<mpq_class> times(const std::array<mpq_class, 2>& x, const std::array<mpq_class, 2>& y) {
  return {x[0] * y[0], x[0] * y[1] + x[1] * y[0], x[1] * y[1]};
}
std::vector<mpq_class> minus(const std::vector<mpq_class>& x, const std::vector<mpq_class>& y) {
  std::vector<mpq_class> out(std::max(x.size(), y.size()), mpq_class(0));
  for (size_t i = 0; i < x.size(); ++i) out[i] += x[i];
  for (size_t i = 0; i < y.size(); ++i) out[i] -= y[i];
  while (out.size() > 1 && out.back() == 0) out.pop_back();
  return out;
}
// det(p, q) of two vectors whose coordinates are linear in u.
std::vector<mpq_class> det(const std::array<std::array<mpq_class, 2>, 2>& p,
                           const std::array<std::array<mpq_class, 2>, 2>& q) {
  return minus(times(p[0], q[1]), times(p[1], q[0]));
}

}  // namespace

namespace {

struct CrossingResiduals {
  double eq6, eq7;
  bool fails;
};

// Condition 3.2 at a crossing vertex (interior, valence 4, a = 0 at the vertex on every
// edge): eqs. (6) and (7) on the first derivatives, with the data seen from the vertex;
// nullopt if v is not a crossing.
std::optional<CrossingResiduals> crossing_residuals(const QuadMesh& mesh, const GluingData& gluing, int v,
                                                    double tolerance) {
  const auto& ring = mesh.ring(v);
  if (ring.boundary || ring.edges.size() != 4) return std::nullopt;
  std::array<double, 4> a{}, da{}, b{}, db_over_b{};
  for (int i = 0; i < 4; ++i) {
    const int e = ring.edges[i];
    const EdgeGluing g = mesh.edge(e).v[0] == v ? *gluing.edges[e] : reversed(*gluing.edges[e]);
    auto at0 = [](const PiecewisePolynomial& p, int order) {
      return order < static_cast<int>(p.pieces[0].size()) ? p.pieces[0][order] : 0.0;
    };
    const double a0 = at0(g.a, 0), a1 = at0(g.a, 1), b0 = at0(g.b, 0), b1 = at0(g.b, 1), c0 = at0(g.c, 0),
                 c1 = at0(g.c, 1);
    a[i] = a0 / c0;
    b[i] = b0 / c0;
    da[i] = (a1 * c0 - a0 * c1) / (c0 * c0);
    db_over_b[i] = b1 / b0 - c1 / c0;
    if (std::abs(a[i]) > tolerance) return std::nullopt;
  }
  CrossingResiduals r;
  r.eq6 = da[0] + db_over_b[3] + b[0] * (da[2] + db_over_b[1]);
  r.eq7 = da[1] + db_over_b[0] + b[1] * (da[3] + db_over_b[2]);
  r.fails = std::abs(r.eq6) > tolerance * (1 + std::abs(da[0]) + std::abs(da[2])) ||
            std::abs(r.eq7) > tolerance * (1 + std::abs(da[1]) + std::abs(da[3]));
  return r;
}

// Surfaces: per vertex the symmetric fan's values seen from it, a = 2cos(2pi/n) (rational or a
// sum of cosines), b = -1, or a skewed fan's; a and b linear along each edge between the two
// ends' values, c = 1. Analysis-suitable by degree. A crossing vertex whose opposite
// neighbours have different valences fails Condition 3.2 with the symmetric values (its
// Taylor image shrinks: docs/G1.md); it gets a skewed fan, which is no crossing, and the
// check runs again (its neighbours now see other values), until no crossing fails.
GluingData surface_gluing(const QuadMesh& mesh) {
  // Skewed: the square fan with its last two directions turned by atan(1/8) (7 degrees), so
  // that neither pair of edges is opposite; rational. The turn was chosen by measurement
  // (docs/G1_POISSON.md, the split pentagonal prism): 1/8 gave the smallest errors of 1/64,
  // 1/16, 1/8, 1/4, 1/2 and 1 at every level; nearer the square the space approaches the
  // crossing's, which loses functions, and further away the parametrization is distorted.
  const mpq_class turn(1, 8);
  const std::array<std::array<mpq_class, 2>, 4> skew{{{1, 0}, {0, 1}, {-1, -turn}, {turn, -1}}};
  std::vector<std::map<int, std::pair<mpq_class, mpq_class>>> skewed(mesh.num_vertices());
  GluingData g;
  for (;;) {
    g = GluingData{};
    g.edges.resize(mesh.num_edges());
    // The end values seen from v along e; the far end's are converted to the edge's frames
    // as in geometric_gluing (B' = 1/B, A' = A/B).
    auto end_values = [&](int v, int e) -> std::pair<CosineSum, mpq_class> {
      if (const auto it = skewed[v].find(e); it != skewed[v].end()) return {CosineSum(it->second.first), it->second.second};
      const auto [p, q] = symmetric_angle(mesh, v);
      if (const auto x = two_cos_pi_exact(p, q)) return {CosineSum(*x), mpq_class(-1)};
      return {CosineSum::two_cos_pi(p, q), mpq_class(-1)};
    };
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const auto& E = mesh.edge(e);
      if (E.boundary()) continue;
      const auto [A0, B0] = end_values(E.v[0], e);
      const auto [A1p, B1p] = end_values(E.v[1], e);
      const mpq_class B1 = 1 / B1p;
      const CosineSum A1 = A1p * B1;
      const std::vector<CosineSum> a{A0, A1 - A0};
      const std::vector<mpq_class> b{B0, B1 - B0};
      EdgeGluing eg;
      if (a[0].cosines.empty() && a[1].cosines.empty())
        eg.a = PiecewisePolynomial::from_exact({std::vector<mpq_class>{a[0].rational, a[1].rational},
                                                std::vector<mpq_class>{a[0].rational, a[1].rational}});
      else
        eg.a = PiecewisePolynomial::from_algebraic({a, a});
      eg.b = b[1] == 0 ? PiecewisePolynomial::constant(b[0]) : PiecewisePolynomial::from_exact({b, b});
      eg.c = PiecewisePolynomial::constant(1);
      g.edges[e] = std::move(eg);
    }
    std::vector<int> failing;
    for (int v = 0; v < mesh.num_vertices(); ++v)
      if (skewed[v].empty())
        if (const auto r = crossing_residuals(mesh, g, v, 1e-10); r && r->fails) failing.push_back(v);
    if (failing.empty()) break;
    for (const int v : failing) {
      const auto& ring = mesh.ring(v);
      for (int i = 0; i < 4; ++i) skewed[v][ring.edges[i]] = fan_values(skew[(i + 3) % 4], skew[i], skew[(i + 1) % 4]);
    }
  }
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (!skewed[v].empty()) g.skewed_fans.push_back(v);
  return g;
}

}  // namespace

GluingData analysis_suitable_gluing(const QuadMesh& mesh) {
  // No plane to take faces from: the symmetric fan's values, skewed where a crossing needs it.
  if (!mesh.planar()) return surface_gluing(mesh);
  // Every bilinear face must be regular: its det J is affine in (s, t) (no s t term), so
  // positive at the four corners means positive everywhere, i.e. a convex face, counter-
  // clockwise.
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 4; ++c) {
      const CornerMap m = corner_map(mesh, f, c);
      if (m.du[0] * m.dv[1] - m.du[1] * m.dv[0] <= 0)
        throw std::invalid_argument("face " + std::to_string(f + 1) + " is not a convex quad (its corner at vertex " +
                                    std::to_string(mesh.face(f)[c] + 1) +
                                    " has an angle of 180 degrees or more, or the face is clockwise): the bilinear "
                                    "map of the face is not regular there");
    }
  // Edges at a vertex that are collinear only up to rounding (a midpoint written with a few
  // digits): exactly, the vertex is not a crossing, but the functions its extra Taylor data
  // bring are dependent to rounding (measured: 10 of 1765 on a mesh written with 6 decimals).
  // Refused by name; exactly collinear edges are a crossing and handled as such.
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto& ring = mesh.ring(v);
    std::vector<std::array<mpq_class, 2>> out;
    std::vector<double> length;
    for (int e : ring.edges) {
      const int w = mesh.edge(e).v[0] == v ? mesh.edge(e).v[1] : mesh.edge(e).v[0];
      out.push_back({mpq_class(mesh.vertex(w).x()) - mpq_class(mesh.vertex(v).x()),
                     mpq_class(mesh.vertex(w).y()) - mpq_class(mesh.vertex(v).y())});
      length.push_back((mesh.vertex(w) - mesh.vertex(v)).head<2>().norm());
    }
    for (size_t i = 0; i < out.size(); ++i)
      for (size_t j = i + 1; j < out.size(); ++j) {
        const mpq_class cross = out[i][0] * out[j][1] - out[i][1] * out[j][0];
        const double relative = std::abs(cross.get_d()) / (length[i] * length[j]);
        if (cross != 0 && relative < 1e-9) {
          char sine[32];
          std::snprintf(sine, sizeof sine, "%.1e", relative);
          throw std::invalid_argument("vertex " + std::to_string(v + 1) + ": two of its edges are collinear only up to "
                                      "rounding (sine of their angle " + sine +
                                      "): write its coordinates so that they lie exactly on the line (a midpoint as "
                                      "the exact average of its ends), or move it off the line");
        }
      }
  }
  // Exact always: a double coordinate is a binary rational, and the data are polynomials in
  // the coordinates, so they are exactly those of the faces (unlike the fan constructions,
  // whose vertex values are only meant up to rounding). Coordinates with 53-bit mantissas
  // give long rationals; the exact rank and null spaces run modulo primes and stay fast
  // (the three-quad mesh, whose coordinates are cos and sin of 30 degrees, converges to
  // 28k dofs in 30 s).
  GluingData g;
  g.edges.resize(mesh.num_edges());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    // f1 = face[0] in its corner frame at v[0] (u along the edge); f0 = face[1] in its corner
    // frame at v[0] (v along the edge): face[1] leaves v[1] at corner[1], so v[0] is its next.
    const CornerMap G1 = corner_map(mesh, E.face[0], E.corner[0]);
    const CornerMap G0 = corner_map(mesh, E.face[1], (E.corner[1] + 1) % 4);
    // Along the edge, as linear polynomials in u: derivatives of G1 at (u, 0), of G0 at (0, u).
    std::array<std::array<mpq_class, 2>, 2> G1u, G1v, G0u, G0v;
    for (int d = 0; d < 2; ++d) {
      G1u[d] = {G1.du[d], 0};
      G1v[d] = {G1.dv[d], G1.duv[d]};
      G0u[d] = {G0.du[d], G0.duv[d]};
      G0v[d] = {G0.dv[d], 0};
    }
    // With the G1 condition c dv G1 = b du G0 + a dv G0 for the map itself, and du G1 = dv G0
    // along the edge: c = det J of G0, b = -det J of G1, a = det(du G0, dv G1).
    const std::vector<mpq_class> c = det(G0u, G0v), b = minus({mpq_class(0)}, det(G1u, G1v)), a = det(G0u, G1v);
    auto function = [](const std::vector<mpq_class>& p) { return PiecewisePolynomial::from_exact({p, p}); };
    g.edges[e] = EdgeGluing{function(a), function(b), function(c)};
  }
  return g;
}

std::vector<std::string> gluing_violations(const QuadMesh& mesh, const GluingData& gluing, double tolerance) {
  std::vector<std::string> out;
  auto edge_name = [&](int e) {
    return "edge " + std::to_string(mesh.edge(e).v[0] + 1) + "-" + std::to_string(mesh.edge(e).v[1] + 1);
  };
  if (static_cast<int>(gluing.edges.size()) != mesh.num_edges()) {
    out.push_back("gluing data for " + std::to_string(gluing.edges.size()) + " edges, the mesh has " +
                  std::to_string(mesh.num_edges()));
    return out;
  }
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if (mesh.edge(e).boundary()) continue;
    if (!gluing.edges[e]) {
      out.push_back(edge_name(e) + ": interior edge without gluing data");
      continue;
    }
    const auto& c = gluing.edges[e]->c;
    for (int h = 0; h < 2; ++h) {
      bool zero = true;
      for (double x : c.pieces[h]) zero = zero && x == 0;
      if (zero) out.push_back(edge_name(e) + ": c is identically 0 on [" + (h ? "1/2, 1" : "0, 1/2") + "]");
    }
    if (c(0) == 0 || c(1) == 0) out.push_back(edge_name(e) + ": c vanishes at an end of the edge");
    if (gluing.edges[e]->b(1) == 0 || gluing.edges[e]->b(0) == 0)
      out.push_back(edge_name(e) + ": b vanishes at an end of the edge (no transition map there)");
  }
  if (!out.empty()) return out;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto& ring = mesh.ring(v);
    if (ring.boundary) continue;
    Eigen::Matrix2d P = Eigen::Matrix2d::Identity();
    for (int e : ring.edges) {
      const EdgeGluing& g = *gluing.edges[e];
      double A, B;
      if (mesh.edge(e).v[0] == v) {
        A = g.a(0) / g.c(0);
        B = g.b(0) / g.c(0);
      } else {  // seen from the far end: B' = 1/B, A' = A/B with A, B at u = 1
        const double A1 = g.a(1) / g.c(1), B1 = g.b(1) / g.c(1);
        A = A1 / B1;
        B = 1 / B1;
      }
      Eigen::Matrix2d M;
      M << 0, 1, B, A;
      // M maps the derivatives in the frame of the face before the edge (clockwise, f0) to the
      // one after it (f1); the ring runs counter-clockwise, so the product around the vertex
      // is M_n ... M_1.
      P = M * P;
    }
    if ((P - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff() <= tolerance && ring.edges.size() == 4) {
      if (const auto r = crossing_residuals(mesh, gluing, v, tolerance); r && r->fails) {
        std::ostringstream s;
        s << "vertex " << v + 1 << " (crossing, valence 4): Condition 3.2 fails, eq. (6) is off by " << r->eq6
          << " and eq. (7) by " << r->eq7;
        out.push_back(s.str());
      }
      continue;
    }
    if ((P - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff() > tolerance) {
      std::ostringstream s;
      s << "vertex " << v + 1 << " (valence " << mesh.valence(v) << "): Condition 3.1 fails, the product of the "
        << "transition jets is [[" << P(0, 0) << ", " << P(0, 1) << "], [" << P(1, 0) << ", " << P(1, 1)
        << "]], not the identity";
      out.push_back(s.str());
    }
  }
  return out;
}

void check_g1_arguments(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  if (k < 2) throw std::invalid_argument("degree k must be >= 2, got " + std::to_string(k));
  if (r < 0 || r >= k) throw std::invalid_argument("split smoothness r must be in [0, k-1], got " + std::to_string(r));
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!mesh.edge(e).boundary() && (e >= static_cast<int>(gluing.edges.size()) || !gluing.edges[e]))
      throw std::invalid_argument("interior edge " + std::to_string(mesh.edge(e).v[0] + 1) + "-" +
                                  std::to_string(mesh.edge(e).v[1] + 1) + " has no gluing data");
}

std::vector<G1ExactRows> g1_condition_rows_per_edge(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  std::vector<G1ExactRows> per_edge(mesh.num_edges());
#pragma omp parallel for schedule(dynamic, 8)
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!mesh.edge(e).boundary()) per_edge[e] = g1_conditions<mpq_class>(mesh, gluing, k, r, e);
  return per_edge;
}

G1SpaceDimension g1_space_dimension_exact(const QuadMesh& mesh, int k, int r, const std::vector<G1ExactRows>& per_edge) {
  G1SpaceDimension d;
  const long n = 2 * k - r + 1;
  d.unknowns = mesh.num_faces() * n * n;
  std::vector<SparseRationalRow> sparse;  // in edge order: the rows' order of the whole system
  for (const auto& rows : per_edge)
    for (const auto& row : rows) sparse.push_back(SparseRationalRow{row});
  d.constraints = static_cast<long>(sparse.size());
  d.rank = rank_reliable(sparse, d.unknowns);
  d.exact = true;
  d.dimension = d.unknowns - d.rank;
  return d;
}

G1SpaceDimension g1_space_dimension_cyclotomic(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  check_g1_arguments(mesh, gluing, k, r);
  if (!gluing.algebraic()) throw std::invalid_argument("g1_space_dimension_cyclotomic: floating-point gluing data");
  G1SpaceDimension d;
  const long n = 2 * k - r + 1;
  d.unknowns = mesh.num_faces() * n * n;
  const long M = gluing.cosine_denominators_lcm();
  d.cyclotomic = 2 * M;
  // The rows of conditions (2) and (3) modulo one prime, at the points g1_conditions uses.
  auto rank_modulo = [&](uint64_t prime, long* constraints) {
    const uint64_t zeta = primitive_root_of_unity(static_cast<uint64_t>(2 * M), prime);
    std::vector<std::vector<std::vector<std::pair<long, uint64_t>>>> per_edge(mesh.num_edges());
#pragma omp parallel
    {
    const ResidueMap residue(prime);
#pragma omp for schedule(dynamic, 8)
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const auto& E = mesh.edge(e);
      if (E.boundary()) continue;
      const EdgeGluing& g = *gluing.edges[e];
      const int f1 = E.face[0], c1 = E.corner[0];
      const int f0 = E.face[1], c0 = (E.corner[1] + 1) % 4;
      auto add = [&](std::vector<std::pair<long, uint64_t>>& row, const FaceFunctional<mpq_class>& f, uint64_t factor) {
        for (const auto& [col, x] : f.terms) row.emplace_back(col, multiply_modulo(residue(x), factor, prime));
      };
      for (const mpq_class& u : condition_points<mpq_class>(g, k)) {
        const mpq_class zero(0);
        std::vector<std::pair<long, uint64_t>> row;
        add(row, shared_face_functional<mpq_class>(f1, c1, u, zero, nullptr, k, r), 1);
        add(row, shared_face_functional<mpq_class>(f0, c0, zero, u, nullptr, k, r), prime - 1);
        per_edge[e].push_back(std::move(row));
        const uint64_t a = g.a.residue(u, residue, zeta, M), b = g.b.residue(u, residue, zeta, M),
                       c = g.c.residue(u, residue, zeta, M);
        row.clear();
        add(row, shared_face_functional<mpq_class>(f1, c1, u, zero, kDv[c1], k, r), c);
        add(row, shared_face_functional<mpq_class>(f0, c0, zero, u, kDu[c0], k, r), (prime - b) % prime);
        add(row, shared_face_functional<mpq_class>(f0, c0, zero, u, kDv[c0], k, r), (prime - a) % prime);
        per_edge[e].push_back(std::move(row));
      }
    }
    }
    std::vector<std::vector<std::pair<long, uint64_t>>> rows;
    for (auto& edge_rows : per_edge)
      for (auto& row : edge_rows) rows.push_back(std::move(row));
    *constraints = static_cast<long>(rows.size());
    return rank_of_residues(rows, d.unknowns, prime);
  };
  // A prime that divides a denominator of the rows cannot take them: the next ones are tried.
  std::vector<long> ranks;
  for (uint64_t prime : primes_congruent_to_one(static_cast<uint64_t>(2 * M), 4)) {
    try {
      ranks.push_back(rank_modulo(prime, &d.constraints));
    } catch (const std::domain_error&) {
      continue;
    }
    if (ranks.size() == 2) break;
  }
  if (ranks.size() < 2) throw std::runtime_error("G1 dimension: no two primes reduce these gluing data");
  if (ranks[0] != ranks[1])
    throw std::runtime_error("G1 dimension: the ranks modulo two primes disagree (" + std::to_string(ranks[0]) + ", " +
                             std::to_string(ranks[1]) + ")");
  d.rank = ranks[0];
  d.dimension = d.unknowns - d.rank;
  return d;
}

G1SpaceDimension g1_space_dimension(const QuadMesh& mesh, const GluingData& gluing, int k, int r, bool floating) {
  check_g1_arguments(mesh, gluing, k, r);
  G1SpaceDimension d;
  const long n = 2 * k - r + 1;
  d.unknowns = mesh.num_faces() * n * n;
  if (gluing.exact() && !floating) {
    return g1_space_dimension_exact(mesh, k, r, g1_condition_rows_per_edge(mesh, gluing, k, r));
  } else {
    const auto rows = g1_conditions<double>(mesh, gluing, k, r);
    d.constraints = static_cast<long>(rows.size());
    d.tolerance = 1e-10;
    Eigen::BDCSVD<Eigen::MatrixXd> svd(dense_rows(rows, d.unknowns));
    svd.setThreshold(d.tolerance);
    d.rank = svd.rank();
  }
  d.dimension = d.unknowns - d.rank;
  return d;
}

}  // namespace knotwork

namespace knotwork {

namespace {

// Rows of the syzygy conditions of one edge's data, over the unknowns: per half h, the
// coefficients (powers of u) of A_h (degree k-1), B_h and C_h (degree k).
template <class Scalar>
std::vector<std::vector<std::pair<long, Scalar>>> syzygy_rows(const EdgeGluing& g, int k, int r) {
  const int na = k, nb = k + 1, per_half = na + 2 * nb;
  auto A = [&](int h, int j) { return static_cast<long>(h * per_half + j); };
  auto B = [&](int h, int j) { return static_cast<long>(h * per_half + na + j); };
  auto C = [&](int h, int j) { return static_cast<long>(h * per_half + na + nb + j); };
  std::vector<std::vector<std::pair<long, Scalar>>> rows;
  const int degree = k + std::max({g.a.degree(), g.b.degree(), g.c.degree(), 0});
  for (int h = 0; h < 2; ++h)
    for (int q = 0; q <= degree; ++q) {  // A a + B b - C c = 0 at degree + 1 points of the half
      const Scalar u = Scalar(h) / 2 + Scalar(q + 1) / (2 * (degree + 2));
      const Scalar a = gluing_value(g.a, u), b = gluing_value(g.b, u), c = gluing_value(g.c, u);
      std::vector<std::pair<long, Scalar>> row;
      Scalar power(1);
      for (int j = 0; j <= k; ++j) {
        if (j < na) row.emplace_back(A(h, j), a * power);
        row.emplace_back(B(h, j), b * power);
        row.emplace_back(C(h, j), -c * power);
        power *= u;
      }
      rows.push_back(std::move(row));
    }
  // Derivatives 0..m of the two pieces agree at u = 1/2 (A: C^{r-1}; B, C: C^r).
  auto smooth = [&](auto column, int count, int order) {
    for (int m = 0; m <= order; ++m) {
      std::vector<std::pair<long, Scalar>> row;
      for (int j = m; j < count; ++j) {
        Scalar d(1);
        for (int i = 0; i < m; ++i) d *= Scalar(j - i);
        for (int i = 0; i < j - m; ++i) d /= 2;
        row.emplace_back(column(0, j), d);
        row.emplace_back(column(1, j), -d);
      }
      rows.push_back(std::move(row));
    }
  };
  smooth(A, na, r - 1);
  smooth(B, nb, r);
  smooth(C, nb, r);
  return rows;
}

}  // namespace

long gluing_syzygy_dimension(const EdgeGluing& g, int k, int r) {
  const long unknowns = 2L * (k + 2 * (k + 1));
  if (g.a.exact && g.b.exact && g.c.exact) {
    const auto rows = syzygy_rows<mpq_class>(g, k, r);
    std::vector<SparseRationalRow> sparse(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) sparse[i].terms = rows[i];
    return unknowns - rank_exact(sparse, unknowns);
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(dense_rows(syzygy_rows<double>(g, k, r), unknowns));
  svd.setThreshold(1e-10);
  return unknowns - svd.rank();
}

std::optional<long> theorem_7_1_dimension(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  if (!mesh.closed()) return std::nullopt;
  const long F2 = mesh.num_faces(), F1 = mesh.num_edges(), F0 = mesh.num_vertices();
  // Crossing vertices: a = 0 at that end of every edge around it (Definition 2.3).
  std::vector<bool> crossing(mesh.num_vertices(), true);
  long syzygies = 0;
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const EdgeGluing& g = *gluing.edges[e];
    if (std::abs(g.a(0) / g.c(0)) > 1e-12) crossing[mesh.edge(e).v[0]] = false;
    if (std::abs(g.a(1) / g.c(1)) > 1e-12) crossing[mesh.edge(e).v[1]] = false;
    syzygies += gluing_syzygy_dimension(g, k, r);
  }
  const long Fplus = std::count(crossing.begin(), crossing.end(), true);
  const long interior = std::max(2L * k - r - 3, 0L);
  return interior * interior * F2 + syzygies + 4 * F2 - 9 * F1 + 3 * F0 + Fplus;
}

}  // namespace knotwork
