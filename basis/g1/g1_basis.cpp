// The local G1 basis of S_k^{1,r} on a quad mesh: vertex, edge, vertex-pair and face
// functions from local null spaces of the G1 conditions (exactly over Q when the gluing
// data are rational), then changes of basis within each vertex that keep the span. Its
// checks, the C0 baseline, the BezierMesh and the fit are in the g1_basis_*.cpp files
// named in basis/g1/README.md.
#include "basis/g1/g1_basis.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "basis/core/bspline_basis.hpp"
#include "basis/exact/sparse_rank.hpp"
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

namespace knotwork {

namespace {

// The local unknowns of one system, in order; corner-block unknowns come first.
struct LocalColumns {
  std::vector<long> global;
  std::unordered_map<long, int> position;
  void add(long c) {
    if (position.emplace(c, static_cast<int>(global.size())).second) global.push_back(c);
  }
  int size() const { return static_cast<int>(global.size()); }
};

void add_corner_block(LocalColumns& cols, int face, int corner, int k, int r) {
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 2; ++a) cols.add(g1_corner_unknown(face, corner, a, b, k, r));
}

// The strip of a face side (corner c to c+1): two rows, corner blocks excluded.
void add_strip(LocalColumns& cols, int face, int corner, int k, int r) {
  const int n = 2 * k - r + 1;
  for (int b = 0; b < 2; ++b)
    for (int a = 2; a <= n - 3; ++a) cols.add(g1_corner_unknown(face, corner, a, b, k, r));
}

void add_edge_strips(LocalColumns& cols, const QuadMesh& mesh, int e, int k, int r) {
  const auto& E = mesh.edge(e);
  for (int side = 0; side < 2; ++side)
    if (E.face[side] >= 0) add_strip(cols, E.face[side], E.corner[side], k, r);
}

template <class Scalar>
using Rows = std::vector<std::vector<std::pair<long, Scalar>>>;

// Rows restricted to the local columns (other unknowns are zero in the local system).
template <class Scalar>
std::vector<std::vector<Scalar>> restrict_rows(const Rows<Scalar>& rows, const LocalColumns& cols) {
  std::vector<std::vector<Scalar>> out;
  for (const auto& row : rows) {
    std::vector<Scalar> dense(cols.size(), Scalar(0));
    bool any = false;
    for (const auto& [c, x] : row) {
      const auto it = cols.position.find(c);
      if (it == cols.position.end()) continue;
      dense[it->second] += x;
      any = true;
    }
    if (any) out.push_back(std::move(dense));
  }
  return out;
}

// The same as sparse rows of (local column, value), for the exact null spaces.
std::vector<std::vector<std::pair<int, mpq_class>>> restrict_rows_sparse(const Rows<mpq_class>& rows,
                                                                         const LocalColumns& cols) {
  std::vector<std::vector<std::pair<int, mpq_class>>> out;
  for (const auto& row : rows) {
    std::vector<std::pair<int, mpq_class>> sparse;
    for (const auto& [c, x] : row)
      if (const auto it = cols.position.find(c); it != cols.position.end()) sparse.emplace_back(it->second, x);
    if (!sparse.empty()) out.push_back(std::move(sparse));
  }
  return out;
}

constexpr double kTolerance = 1e-10;

// Null space in floating point: right singular vectors of singular values below
// kTolerance * largest from a double SVD, then one step of iterative refinement with the
// residual in long double (the rows are computed in long double too). Without the step the
// null vectors are accurate only to about eps / (the smallest singular value kept), and for
// data that are not analysis-suitable that value falls about 4x per subdivision. Measured with
// `geometric` data on the pentagon with decimal coordinates (k = 5), H1 errors at 3, 4 and 5
// subdivisions: 1.4e-7, 6.4e-7, 5.3e-6 without the step, 1.4e-7, 6.5e-9, 3.1e-10 with it (the
// exact path on binary coordinates: 1.5e-7, 7.1e-9, 8.8e-10). An SVD in long double throughout
// was as accurate and took 3 to 5 times as long.
Eigen::MatrixXd null_space(const std::vector<std::vector<long double>>& rows, int m) {
  if (rows.empty()) return Eigen::MatrixXd::Identity(m, m);
  using MatrixL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  MatrixL A(static_cast<Eigen::Index>(rows.size()), m);
  for (size_t i = 0; i < rows.size(); ++i)
    for (int j = 0; j < m; ++j) A(static_cast<Eigen::Index>(i), j) = rows[i][j];
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A.cast<double>(), Eigen::ComputeThinU | Eigen::ComputeFullV);
  svd.setThreshold(kTolerance);
  const Eigen::Index rank = svd.rank();
  Eigen::MatrixXd N = svd.matrixV().rightCols(m - rank);
  if (rank == 0 || N.cols() == 0) return N;
  // N <- N - A+ (A N): the residual exact to long double, A+ from the double factors.
  const Eigen::MatrixXd residual = (A * N.cast<long double>()).cast<double>();
  N -= svd.matrixV().leftCols(rank) *
       (svd.singularValues().head(rank).cwiseInverse().asDiagonal() * (svd.matrixU().leftCols(rank).transpose() * residual));
  return N;
}

// Functions with independent Taylor data (the first `taylor` local unknowns) among the
// null-space vectors: column elimination on the Taylor rows, exactly.
std::vector<std::vector<mpq_class>> taylor_independent(std::vector<std::vector<mpq_class>> Z, int taylor) {
  std::vector<bool> used(Z.size(), false);
  std::vector<size_t> chosen;
  for (int t = 0; t < taylor; ++t) {
    size_t j = 0;
    while (j < Z.size() && (used[j] || Z[j][t] == 0)) ++j;
    if (j == Z.size()) continue;
    used[j] = true;
    chosen.push_back(j);
    const mpq_class inv = 1 / Z[j][t];
    for (auto& x : Z[j]) x *= inv;
    for (size_t l = 0; l < Z.size(); ++l) {
      if (l == j || Z[l][t] == 0) continue;
      const mpq_class f = Z[l][t];
      for (size_t i = 0; i < Z[l].size(); ++i)
        if (Z[j][i] != 0) Z[l][i] -= f * Z[j][i];
    }
  }
  std::vector<std::vector<mpq_class>> out;
  for (size_t j : chosen) out.push_back(std::move(Z[j]));
  return out;
}

// The same in floating point: Z times the right singular vectors of its Taylor rows.
Eigen::MatrixXd taylor_independent(const Eigen::MatrixXd& Z, int taylor) {
  if (Z.cols() == 0) return Z;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Z.topRows(taylor), Eigen::ComputeFullV);
  const auto& sv = svd.singularValues();
  Eigen::Index rank = 0;
  for (Eigen::Index i = 0; i < sv.size(); ++i) rank += sv(i) > kTolerance * std::max(sv(0), 1.0);
  return Z * svd.matrixV().leftCols(rank);
}

double to_double(const mpq_class& x) { return x.get_d(); }
double to_double(double x) { return x; }

// A local solution (std::vector<mpq_class> or Eigen::VectorXd over `cols`) as a function.
template <class Vector>
G1BasisFunction make_function(G1BasisFunction::Kind kind, int owner, const LocalColumns& cols, const Vector& x) {
  G1BasisFunction f{kind, owner, {}};
  for (int i = 0; i < cols.size(); ++i)
    if (x[i] != 0) f.coefficients.emplace_back(cols.global[i], to_double(x[i]));
  return f;
}

// The Taylor part (the first `taylor` local unknowns: corner blocks) of an exact solution.
std::map<long, mpq_class> taylor_part(const LocalColumns& cols, const std::vector<mpq_class>& x, int taylor) {
  std::map<long, mpq_class> t;
  for (int i = 0; i < taylor; ++i)
    if (x[i] != 0) t.emplace(cols.global[i], x[i]);
  return t;
}

// y -= f * x on sparse vectors, dropping the entries that become zero.
void subtract_scaled(std::map<long, mpq_class>& y, const mpq_class& f, const std::map<long, mpq_class>& x) {
  for (const auto& [c, v] : x) {
    mpq_class& z = y[c];
    z -= f * v;
    if (z == 0) y.erase(c);
  }
}

template <class Scalar>
Rows<Scalar> edge_rows(const QuadMesh& mesh, const GluingData& gluing, int k, int r, int e) {
  if constexpr (std::is_same_v<Scalar, mpq_class>)
    return g1_condition_rows_exact(mesh, gluing, k, r, e);
  else if constexpr (std::is_same_v<Scalar, long double>)
    return g1_condition_rows_long(mesh, gluing, k, r, e);
  else
    return g1_condition_rows(mesh, gluing, k, r, e);
}

// Span of the Taylor data (corner-block coefficients) of the functions kept so far, over Q:
// a row echelon form keyed by leading column. A vector is reduced column by column upwards,
// each step touching only the pivot it meets (a reduced form kept fully reduced cost a pass
// over every stored vector per addition: quadratic in the vertex functions, 1.4 s at 61k
// dofs).
class ExactTaylorSpan {
 public:
  // Records t and returns true when it is independent of the span.
  bool add(std::map<long, mpq_class> t) {
    // Subtracting a stored vector (zero before its pivot) changes only columns at or after the
    // pivot: after the sweep t is zero at every pivot column.
    for (auto it = t.begin(); it != t.end();) {
      const long column = it->first;
      const auto pivot = stored_.find(column);
      if (pivot == stored_.end()) {
        ++it;
        continue;
      }
      subtract_scaled(t, mpq_class(it->second), pivot->second);
      it = t.upper_bound(column);
    }
    if (t.empty()) return false;
    const long p = t.begin()->first;
    const mpq_class inv = 1 / t.begin()->second;
    for (auto& [c, x] : t) x *= inv;
    stored_.emplace(p, std::move(t));
    return true;
  }

 private:
  std::map<long, std::map<long, mpq_class>> stored_;  // leading column -> vector with 1 there
};

// The same in floating point, for the functions beyond the vertex functions: an orthonormal
// basis of their Taylor data modulo the vertex functions' (which live on disjoint vertex
// blocks, so the quotient is a projection per vertex block).
struct FloatTaylorSpan {
  std::map<long, Eigen::MatrixXd> vertex_basis;  // vertex -> orthonormal columns on its corner blocks
  std::vector<std::map<long, double>> extra;     // orthonormal, over corner unknowns
};

struct PairSystem {
  LocalColumns cols;
  std::vector<int> block_vertex;  // per Taylor column: the vertex of its corner block
  int taylor = 0;
  std::set<int> edges;            // the interior edges at either end
};

// The system on the faces around the given vertices: their corner blocks, then the strips of
// their interior edges.
PairSystem patch_system(const QuadMesh& mesh, const std::vector<int>& vertices, int k, int r) {
  PairSystem sys;
  for (const int v : vertices) {
    const auto& ring = mesh.ring(v);
    for (size_t i = 0; i < ring.faces.size(); ++i) {
      add_corner_block(sys.cols, ring.faces[i], ring.corners[i], k, r);
      sys.block_vertex.resize(sys.cols.size(), v);
    }
    for (int x : ring.edges)
      if (!mesh.edge(x).boundary()) sys.edges.insert(x);
  }
  sys.taylor = sys.cols.size();
  for (int x : sys.edges) add_edge_strips(sys.cols, mesh, x, k, r);
  return sys;
}

PairSystem pair_system(const QuadMesh& mesh, int e, int k, int r) {
  return patch_system(mesh, {mesh.edge(e).v[0], mesh.edge(e).v[1]}, k, r);
}

// One edge's exact conditions in reduced echelon form on its strips, with the corner blocks at
// both ends carried along (basis/exact: leading_echelon). The space's dimension, the vertex
// systems at the edge's two ends and its own edge functions are all read off this one
// elimination; before, the dimension was a rank of the whole system and each of the three
// local systems eliminated the strips again (most of a G1 build on a mesh with 17-digit
// coordinates).
struct EdgeEchelon {
  LocalColumns cols;  // the strips (add_edge_strips), then every other unknown of the rows
  std::shared_ptr<const LeadingEchelon> echelon;
};

// Every edge's echelon (boundary edges: no rows, every strip free), shared between edges whose
// local systems are equal entry for entry (after a subdivision, most inner edges of a coarse
// face).
std::vector<EdgeEchelon> eliminate_strips(const QuadMesh& mesh, const std::vector<Rows<mpq_class>>& rows, int k,
                                          int r) {
  std::vector<EdgeEchelon> out(mesh.num_edges());
  std::mutex mutex;
  std::map<std::vector<std::vector<std::pair<int, mpq_class>>>, std::shared_ptr<const LeadingEchelon>> cache;
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < mesh.num_edges(); ++e) {
    EdgeEchelon& E = out[e];
    add_edge_strips(E.cols, mesh, e, k, r);
    const int strips = E.cols.size();
    for (const auto& row : rows[e])
      for (const auto& term : row) E.cols.add(term.first);
    auto A = restrict_rows_sparse(rows[e], E.cols);
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (const auto it = cache.find(A); it != cache.end()) E.echelon = it->second;
    }
    if (E.echelon) continue;
    auto echelon = std::make_shared<const LeadingEchelon>(leading_echelon(A, E.cols.size(), strips));
    const std::lock_guard<std::mutex> lock(mutex);
    E.echelon = cache.emplace(std::move(A), std::move(echelon)).first->second;
  }
  return out;
}

// The dimension from the echelons: a strip belongs to one edge's rows only, so the rank of
// the whole system is the number of strip pivots (exact) plus the rank of the rows left on
// the corner blocks, modulo primes (rank_reliable, as for the whole system before; about a
// third of its rows and none of the strips).
G1SpaceDimension dimension_from_strips(const QuadMesh& mesh, int k, int r,
                                                      const std::vector<EdgeEchelon>& echelons, long constraints) {
  G1SpaceDimension d;
  const long n = 2 * k - r + 1;
  d.unknowns = mesh.num_faces() * n * n;
  d.constraints = constraints;
  std::vector<int> owner(d.unknowns, -1);
  for (int e = 0; e < mesh.num_edges(); ++e)
    for (int j = 0; j < echelons[e].echelon->leading; ++j) {
      int& o = owner[echelons[e].cols.global[j]];
      if (o >= 0) throw std::logic_error("G1 dimension: a strip unknown belongs to two edges");
      o = e;
    }
  long pivots = 0;
  std::vector<SparseRationalRow> corner_rows;
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const EdgeEchelon& E = echelons[e];
    const LeadingEchelon& L = *E.echelon;
    for (int j = L.leading; j < L.columns; ++j)
      if (owner[E.cols.global[j]] >= 0) throw std::logic_error("G1 dimension: an edge's rows meet another edge's strip");
    pivots += static_cast<long>(L.pivot_column.size());
    for (size_t i = L.pivot_column.size(); i < L.rows.size(); ++i) {
      SparseRationalRow row;
      for (int j = L.leading; j < L.columns; ++j)
        if (L.rows[i][j] != 0) row.terms.emplace_back(E.cols.global[j], mpq_class(L.rows[i][j]));
      corner_rows.push_back(std::move(row));
    }
  }
  d.rank = pivots + rank_reliable(corner_rows, d.unknowns);
  d.exact = true;
  d.dimension = d.unknowns - d.rank;
  return d;
}

// The null vectors of a vertex system (corner blocks, the first `taylor` of `cols`, then the
// strips of `edges`) that have independent Taylor data: one per free corner-block column of
// the reduced echelon form with the strips eliminated first, the same vectors as that form
// gives (the others, free strip columns, vanish on the corner blocks: they are edge
// functions). Each edge's strip rows are already reduced, and its rows without strips
// constrain the corner blocks alone, so only those are solved together here; the strips
// then follow row by row. (That no edge's rows meet another edge's strips, the premise, is
// checked once for the whole mesh by dimension_from_strips.)
std::vector<std::vector<mpq_class>> vertex_null_space(const LocalColumns& cols, int taylor,
                                                                     const std::vector<const EdgeEchelon*>& edges) {
  std::vector<std::vector<int>> at(edges.size());  // per edge column: the vertex's corner column, or -1
  std::vector<std::vector<mpq_class>> corner_rows;
  for (size_t b = 0; b < edges.size(); ++b) {
    const LeadingEchelon& L = *edges[b]->echelon;
    at[b].assign(L.columns, -1);
    for (int j = L.leading; j < L.columns; ++j) {
      const auto it = cols.position.find(edges[b]->cols.global[j]);
      if (it == cols.position.end()) continue;  // the far end's corner blocks: zero here
      at[b][j] = it->second;
    }
    for (size_t i = L.pivot_column.size(); i < L.rows.size(); ++i) {
      std::vector<mpq_class> row(taylor, mpq_class(0));
      bool any = false;
      for (int j = L.leading; j < L.columns; ++j)
        if (at[b][j] >= 0 && L.rows[i][j] != 0) {
          row[at[b][j]] = L.rows[i][j];
          any = true;
        }
      if (any) corner_rows.push_back(std::move(row));
    }
  }
  std::vector<std::vector<mpq_class>> out;
  mpq_class sum;
  for (auto& tau : null_space_exact(std::move(corner_rows), taylor)) {
    std::vector<mpq_class> x(cols.size(), mpq_class(0));
    std::move(tau.begin(), tau.end(), x.begin());
    for (size_t b = 0; b < edges.size(); ++b) {
      const LeadingEchelon& L = *edges[b]->echelon;
      for (size_t i = 0; i < L.pivot_column.size(); ++i) {
        sum = 0;
        for (int j = L.leading; j < L.columns; ++j)
          if (at[b][j] >= 0 && L.rows[i][j] != 0 && x[at[b][j]] != 0) sum += L.rows[i][j] * x[at[b][j]];
        if (sum == 0) continue;
        const int pivot = L.pivot_column[i];
        x[cols.position.at(edges[b]->cols.global[pivot])] = -sum / L.rows[i][pivot];
      }
    }
    out.push_back(std::move(x));
  }
  return out;
}

template <class Scalar>
void build(const QuadMesh& mesh, const GluingData& gluing, G1Basis& basis,
           const std::function<void(const std::string&)>& say, std::vector<Rows<Scalar>> rows = {},
           std::vector<EdgeEchelon> edge_echelon = {}) {  // exact: both given, from g1_basis
  const int k = basis.k, r = basis.r, n = 2 * k - r + 1;
  // Independent per edge and per vertex: threaded (the exact arithmetic dominates a G1 build).
  // The exact path gets the rows the dimension was computed from.
  if (rows.empty()) {
    rows.resize(mesh.num_edges());
#pragma omp parallel for schedule(dynamic, 8)
    for (int e = 0; e < mesh.num_edges(); ++e)
      if (!mesh.edge(e).boundary()) rows[e] = edge_rows<Scalar>(mesh, gluing, k, r, e);
  }
  constexpr bool exact = std::is_same_v<Scalar, mpq_class>;
  ExactTaylorSpan exact_span;
  FloatTaylorSpan float_span;

  // Each vertex's local solutions, computed in parallel, then kept in vertex order.
  struct VertexSolutions {
    LocalColumns cols;
    int taylor = 0;
    std::shared_ptr<const std::vector<std::vector<mpq_class>>> exact;  // shared by equal configurations
    Eigen::MatrixXd floating;
  };
  std::vector<VertexSolutions> local(mesh.num_vertices());
  say("vertex functions, " + std::to_string(mesh.num_vertices()) + " vertices");
  // A vertex's local system, with its columns and rows taken in ring order, depends only on
  // its configuration: the valence, whether it is on the boundary, and per edge around it
  // whether the edge is a boundary edge, which way it runs and its data. After a subdivision
  // most vertices share one (the inside of a coarse face has the parametric data on every
  // edge), so the exact solutions (reduced row echelon form: canonical for the column order)
  // are computed once per configuration.
  std::mutex cache_mutex;
  std::map<std::string, std::shared_ptr<const std::vector<std::vector<mpq_class>>>> cache;
  std::map<std::vector<std::vector<Scalar>>, std::shared_ptr<const Eigen::MatrixXd>> floating_cache;
  auto configuration = [&](int v) {
    const auto& ring = mesh.ring(v);
    std::string key = std::to_string(ring.faces.size()) + (ring.boundary ? "b" : "i");
    for (int e : ring.edges) {
      const auto& E = mesh.edge(e);
      key += E.boundary() ? "|B" : (E.v[0] == v ? "|0" : "|1");
      if (E.boundary()) continue;
      for (const PiecewisePolynomial* p : {&gluing.edges[e]->a, &gluing.edges[e]->b, &gluing.edges[e]->c})
        for (int h = 0; h < 2; ++h) {
          key += h ? ";" : ",";
          for (const auto& x : (*p->exact)[h]) key += x.get_str() + " ";
        }
    }
    return key;
  };
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto& ring = mesh.ring(v);
    LocalColumns& cols = local[v].cols;
    for (size_t i = 0; i < ring.faces.size(); ++i) add_corner_block(cols, ring.faces[i], ring.corners[i], k, r);
    const int taylor = local[v].taylor = cols.size();
    std::vector<int> edges;  // each once (ring.edges closes the fan on the boundary)
    for (int e : ring.edges)
      if (!mesh.edge(e).boundary() && std::find(edges.begin(), edges.end(), e) == edges.end()) edges.push_back(e);
    for (int e : edges) add_edge_strips(cols, mesh, e, k, r);
    if constexpr (exact) {
      const std::string key = configuration(v);
      std::shared_ptr<const std::vector<std::vector<mpq_class>>> solutions;
      {
        const std::lock_guard<std::mutex> lock(cache_mutex);
        if (const auto it = cache.find(key); it != cache.end()) solutions = it->second;
      }
      if (!solutions) {
        std::vector<const EdgeEchelon*> echelons;
        for (int e : edges) echelons.push_back(&edge_echelon[e]);
        solutions = std::make_shared<const std::vector<std::vector<mpq_class>>>(
            taylor_independent(vertex_null_space(cols, taylor, echelons), taylor));
        const std::lock_guard<std::mutex> lock(cache_mutex);
        cache.emplace(key, solutions);
      }
      local[v].exact = std::move(solutions);
    } else {
      // The same sharing, keyed by the local system itself (equal doubles, equal solutions).
      Rows<Scalar> vertex_rows;
      for (int e : edges) vertex_rows.insert(vertex_rows.end(), rows[e].begin(), rows[e].end());
      auto A = restrict_rows(vertex_rows, cols);
      std::shared_ptr<const Eigen::MatrixXd> solutions;
      {
        const std::lock_guard<std::mutex> lock(cache_mutex);
        if (const auto it = floating_cache.find(A); it != floating_cache.end()) solutions = it->second;
      }
      if (!solutions) {
        solutions = std::make_shared<const Eigen::MatrixXd>(taylor_independent(null_space(A, cols.size()), taylor));
        const std::lock_guard<std::mutex> lock(cache_mutex);
        floating_cache.emplace(std::move(A), solutions);
      }
      local[v].floating = *solutions;
    }
  }
  std::vector<G1BasisFunction> vertex_functions;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const LocalColumns& cols = local[v].cols;
    const int taylor = local[v].taylor;
    if constexpr (exact) {
      for (const auto& x : *local[v].exact) {
        vertex_functions.push_back(make_function(G1BasisFunction::Kind::vertex, v, cols, x));
        exact_span.add(taylor_part(cols, x, taylor));
      }
    } else {
      const Eigen::MatrixXd& Z = local[v].floating;
      for (Eigen::Index j = 0; j < Z.cols(); ++j)
        vertex_functions.push_back(make_function(G1BasisFunction::Kind::vertex, v, cols, Z.col(j)));
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(Z.topRows(taylor));
      float_span.vertex_basis[v] =
          qr.householderQ() * Eigen::MatrixXd::Identity(taylor, std::min<Eigen::Index>(Z.cols(), taylor));
    }
  }
  local.clear();

  // Edge functions: each edge's null space on its strips, in parallel. Exact: read off the
  // edge's echelon, once per distinct echelon (edges with equal systems share one).
  say("edge functions, " + std::to_string(mesh.num_edges()) + " edges");
  std::vector<LocalColumns> edge_cols(mesh.num_edges());
  std::vector<std::shared_ptr<const std::vector<std::vector<mpq_class>>>> edge_exact(mesh.num_edges());
  std::vector<Eigen::MatrixXd> edge_floating(exact ? 0 : mesh.num_edges());
  std::map<const LeadingEchelon*, std::shared_ptr<const std::vector<std::vector<mpq_class>>>> echelon_cache;
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < mesh.num_edges(); ++e) {
    add_edge_strips(edge_cols[e], mesh, e, k, r);
    if constexpr (exact) {
      // The strips' null space with the corner blocks zero.
      const LeadingEchelon* echelon = edge_echelon[e].echelon.get();
      {
        const std::lock_guard<std::mutex> lock(cache_mutex);
        if (const auto it = echelon_cache.find(echelon); it != echelon_cache.end()) edge_exact[e] = it->second;
      }
      if (edge_exact[e]) continue;
      auto solutions = std::make_shared<const std::vector<std::vector<mpq_class>>>(leading_null_space(*echelon));
      const std::lock_guard<std::mutex> lock(cache_mutex);
      edge_exact[e] = echelon_cache.emplace(echelon, std::move(solutions)).first->second;
    } else {
      edge_floating[e] = null_space(restrict_rows(rows[e], edge_cols[e]), edge_cols[e].size());
    }
  }
  std::vector<G1BasisFunction> edge_functions;
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if constexpr (exact) {
      for (const auto& x : *edge_exact[e])
        edge_functions.push_back(make_function(G1BasisFunction::Kind::edge, e, edge_cols[e], x));
    } else {
      const Eigen::MatrixXd& Z = edge_floating[e];
      for (Eigen::Index j = 0; j < Z.cols(); ++j)
        edge_functions.push_back(make_function(G1BasisFunction::Kind::edge, e, edge_cols[e], Z.col(j)));
    }
  }
  edge_cols.clear();
  edge_exact.clear();
  edge_echelon.clear();
  edge_floating.clear();
  const long face_count = static_cast<long>(mesh.num_faces()) * std::max(n - 4, 0) * std::max(n - 4, 0);

  // Below the separability of an edge, the Taylor data at its two ends are coupled and the
  // vertex functions miss part of the Taylor map's image: solutions on the faces around
  // both ends supply it (kind vertex_pair, one edge at a time, while something is missing).
  const long wanted = basis.space.dimension - static_cast<long>(edge_functions.size()) - face_count;
  long have = static_cast<long>(vertex_functions.size());
  // Exact: the solutions whose Taylor data add to the span, until nothing is missing.
  auto keep_independent = [&](G1BasisFunction::Kind kind, int owner, const LocalColumns& cols,
                              const std::vector<std::vector<mpq_class>>& solutions, int taylor) {
    for (const auto& x : solutions) {
      if (have == wanted) return;
      if (!exact_span.add(taylor_part(cols, x, taylor))) continue;
      vertex_functions.push_back(make_function(kind, owner, cols, x));
      ++have;
    }
  };
  for (int e = 0; e < mesh.num_edges() && have < wanted; ++e) {
    if (mesh.edge(e).boundary()) continue;
    const PairSystem sys = pair_system(mesh, e, k, r);
    Rows<Scalar> pair_rows;
    for (int x : sys.edges) pair_rows.insert(pair_rows.end(), rows[x].begin(), rows[x].end());
    const auto A = restrict_rows(pair_rows, sys.cols);
    if constexpr (exact) {
      keep_independent(G1BasisFunction::Kind::vertex_pair, e, sys.cols, null_space_exact(A, sys.cols.size()), sys.taylor);
    } else {
      const Eigen::MatrixXd Z = null_space(A, sys.cols.size());
      // Taylor rows modulo the vertex functions, block by block.
      Eigen::MatrixXd R = Z.topRows(sys.taylor);
      for (const int v : {mesh.edge(e).v[0], mesh.edge(e).v[1]}) {
        std::vector<Eigen::Index> at;
        for (int i = 0; i < sys.taylor; ++i)
          if (sys.block_vertex[i] == v) at.push_back(i);
        const Eigen::MatrixXd& Q = float_span.vertex_basis[v];
        Eigen::MatrixXd block(static_cast<Eigen::Index>(at.size()), Z.cols());
        for (size_t i = 0; i < at.size(); ++i) block.row(static_cast<Eigen::Index>(i)) = R.row(at[i]);
        block -= Q * (Q.transpose() * block);
        for (size_t i = 0; i < at.size(); ++i) R.row(at[i]) = block.row(static_cast<Eigen::Index>(i));
      }
      // ... and modulo the pair functions kept so far (twice, for orthogonality).
      for (int pass = 0; pass < 2; ++pass)
        for (const auto& q : float_span.extra) {
          Eigen::RowVectorXd dot = Eigen::RowVectorXd::Zero(Z.cols());
          std::vector<std::pair<int, double>> local;
          for (int i = 0; i < sys.taylor; ++i) {
            const auto it = q.find(sys.cols.global[i]);
            if (it != q.end()) local.emplace_back(i, it->second);
          }
          for (const auto& [i, x] : local) dot += x * R.row(i);
          for (const auto& [i, x] : local) R.row(i) -= x * dot;
        }
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const auto& sv = svd.singularValues();
      for (Eigen::Index j = 0; j < sv.size() && have < wanted; ++j) {
        if (sv(j) <= kTolerance) break;
        vertex_functions.push_back(make_function(G1BasisFunction::Kind::vertex_pair, e, sys.cols,
                                                 Eigen::VectorXd(Z * svd.matrixV().col(j))));
        std::map<long, double> q;
        for (int i = 0; i < sys.taylor; ++i)
          if (svd.matrixU()(i, j) != 0) q.emplace(sys.cols.global[i], svd.matrixU()(i, j));
        float_span.extra.push_back(std::move(q));
        ++have;
      }
    }
  }

  // Still short (Taylor data coupled across more than one edge): exact solutions on the faces
  // around the four corners of one face at a time, still local (kind coupled).
  if constexpr (exact) {
    for (int f = 0; f < mesh.num_faces() && have < wanted; ++f) {
      const auto& q = mesh.face(f);
      const PairSystem sys = patch_system(mesh, {q[0], q[1], q[2], q[3]}, k, r);
      Rows<Scalar> patch_rows;
      for (int x : sys.edges) patch_rows.insert(patch_rows.end(), rows[x].begin(), rows[x].end());
      keep_independent(G1BasisFunction::Kind::coupled, -1, sys.cols,
                       null_space_exact(restrict_rows(patch_rows, sys.cols), sys.cols.size()), sys.taylor);
    }
  }
  if (have < wanted) {
    if constexpr (exact) {
      // Exactly, on every corner block and strip (face interiors are in no condition).
      LocalColumns cols;
      for (int f = 0; f < mesh.num_faces(); ++f)
        for (int c = 0; c < 4; ++c) add_corner_block(cols, f, c, k, r);
      const int taylor = cols.size();
      for (int e = 0; e < mesh.num_edges(); ++e) add_edge_strips(cols, mesh, e, k, r);
      Rows<Scalar> all;
      for (const auto& x : rows) all.insert(all.end(), x.begin(), x.end());
      // The exact global system is dense here: refuse what cannot fit rather than exhaust memory.
      if (static_cast<double>(all.size()) * cols.size() > 3e7)
        throw std::runtime_error("the local constructions leave " + std::to_string(wanted - have) +
                                 " functions of S_" + std::to_string(k) + "^{1," + std::to_string(r) +
                                 "} undetermined, and the global completion is too large for this mesh (" +
                                 std::to_string(mesh.num_faces()) + " faces)");
      keep_independent(G1BasisFunction::Kind::coupled, -1, cols, null_space_exact(restrict_rows(all, cols), cols.size()),
                       taylor);
    } else {
      // Floating-point data have no local construction beyond vertex pairs. A global SVD of
      // every condition used to complete them: minutes at 7 000 unknowns, and on the one mesh
      // measured (valence 5, symmetric_c1 data, one subdivision) a basis whose solution was
      // off by 0.24 in L2 (level 0: 0.018). Refused instead.
      throw std::runtime_error("the local constructions leave " + std::to_string(wanted - have) + " functions of S_" +
                               std::to_string(k) + "^{1," + std::to_string(r) +
                               "} undetermined for these floating-point gluing data (their Taylor data are coupled "
                               "across more than one edge); knotwork completes such spaces only with rational data: "
                               "use gluing = \"analysis_suitable\" (the default), rational data, or a higher degree");
    }
  }
  basis.functions = std::move(vertex_functions);
  for (auto& f : edge_functions) basis.functions.push_back(std::move(f));
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int i = 2; i <= n - 3; ++i)
      for (int j = 2; j <= n - 3; ++j)
        basis.functions.push_back({G1BasisFunction::Kind::face, f, {{g1_unknown(f, i, j, k, r), 1.0}}});
}

// The functions of each vertex and edge (by owner), for the changes of basis below.
struct FunctionsByOwner {
  std::vector<std::vector<int>> vertex, edge;
  std::vector<int> pairs;
  FunctionsByOwner(const QuadMesh& mesh, const G1Basis& basis) : vertex(mesh.num_vertices()), edge(mesh.num_edges()) {
    for (size_t j = 0; j < basis.functions.size(); ++j) {
      const auto& f = basis.functions[j];
      if (f.kind == G1BasisFunction::Kind::edge) edge[f.owner].push_back(static_cast<int>(j));
      if (f.kind == G1BasisFunction::Kind::vertex) vertex[f.owner].push_back(static_cast<int>(j));
      if (f.kind == G1BasisFunction::Kind::vertex_pair) pairs.push_back(static_cast<int>(j));
    }
  }
};

// Adds the coefficients of the functions to the local columns.
void add_columns(const G1Basis& basis, const std::vector<int>& which, LocalColumns& cols) {
  for (int j : which)
    for (const auto& [c, x] : basis.functions[j].coefficients) cols.add(c);
}

// The functions as dense columns over `cols` (which holds all their coefficients).
Eigen::MatrixXd dense_columns(const G1Basis& basis, const std::vector<int>& which, LocalColumns& cols) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(cols.size(), static_cast<Eigen::Index>(which.size()));
  for (size_t i = 0; i < which.size(); ++i)
    for (const auto& [c, x] : basis.functions[which[i]].coefficients) M(cols.position[c], static_cast<Eigen::Index>(i)) = x;
  return M;
}

// Replaces function `id` by the dense column x over `cols`. Entries at rounding level are
// dropped, to keep the supports sparse, and so are the unknowns in `zero` (exact zeros).
void store_column(G1Basis& basis, int id, const Eigen::Ref<const Eigen::VectorXd>& x, const LocalColumns& cols,
                  const std::set<long>* zero = nullptr) {
  const double drop = 1e-14 * x.cwiseAbs().maxCoeff();
  auto& coefficients = basis.functions[id].coefficients;
  coefficients.clear();
  for (int row = 0; row < cols.size(); ++row)
    if (std::abs(x(row)) > drop && !(zero && zero->count(cols.global[row]))) coefficients.emplace_back(cols.global[row], x(row));
}

// Removes from the columns of X their least-squares part in the span of O.
void project_out(Eigen::MatrixXd& X, const Eigen::MatrixXd& O) {
  if (O.cols() > 0) X -= O * O.colPivHouseholderQr().solve(X);
}

// An orthonormal basis of the columns' span (thin Householder QR; the columns are independent).
Eigen::MatrixXd orthonormal_columns(const Eigen::MatrixXd& X) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(X);
  return qr.householderQ() * Eigen::MatrixXd::Identity(X.rows(), X.cols());
}

// The span of X (independent columns, row 0 the value at the vertex) as: first the function
// of the span with value 1 there that is orthogonal to the rest, then an orthonormal basis of
// the functions of the span that vanish there. With Q orthonormal and q0 its row 0, the first
// is Q q0^T / |q0|^2, and the rest Q times a Householder reflection's columns orthogonal to q0.
Eigen::MatrixXd value_first_orthogonal(const Eigen::MatrixXd& X) {
  const Eigen::MatrixXd Q = orthonormal_columns(X);
  const Eigen::VectorXd q0 = Q.row(0).transpose();
  const double size = q0.norm();
  if (!(size > 1e-12)) return Q;  // nothing of the span has a value there
  const Eigen::Index m = Q.cols();
  const Eigen::VectorXd u = q0 / size;
  Eigen::MatrixXd H = Eigen::MatrixXd::Identity(m, m);  // H u = e0, H orthogonal and symmetric
  Eigen::VectorXd w = u;
  w(0) -= 1;
  if (w.norm() > 1e-14) {
    w.normalize();
    H -= 2 * w * w.transpose();
  }
  Eigen::MatrixXd out = Q * H;
  out.col(0) = Q * (u / size);
  return out;
}

// The functions of each interior edge, replaced by an orthonormal basis (coefficient space) of
// their span: the exact echelon form's solutions can be far from orthogonal.
void tidy_edge_functions(const QuadMesh& mesh, G1Basis& basis) {
  const FunctionsByOwner by(mesh, basis);
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const std::vector<int>& ids = by.edge[e];
    if (ids.size() < 2 || mesh.edge(e).boundary()) continue;
    LocalColumns cols;
    add_columns(basis, ids, cols);
    const Eigen::MatrixXd Q = orthonormal_columns(dense_columns(basis, ids, cols));
    for (size_t i = 0; i < ids.size(); ++i) store_column(basis, ids[i], Q.col(static_cast<Eigen::Index>(i)), cols);
  }
}

// Two changes of basis within each vertex's functions, which keep the span:
// - a vertex function plus any edge function of its edges is as good a vertex function; keep
//   the one orthogonal to them (coefficient space), which removes the large bumps along the
//   edges that the echelon form leaves (the paper's printed functions have them too);
// - then value_first_orthogonal: the first is the one with value 1 at the vertex (what users
//   plot, and what the paper lists first), the others vanish there and are orthonormal.
// The second step is what makes the basis as well conditioned as a B-spline basis. Before, the
// functions were the elimination's solutions with the value function's multiples subtracted,
// nearly dependent at every vertex: on cases/g1_mixed_valences.toml the Jacobi-scaled
// stiffness had condition 2.9e4, 1.9e6 and 3.2e6 over three levels (now 1.7e2, 5.1e2, 2.1e3,
// the C0 space's 3.5e2, 7.9e2, 3.3e3), its smallest eigenvector 99% on vertex functions of
// valence-4 vertices, and CG did not converge with any preconditioner (docs/G1_POISSON.md).
void tidy_vertex_functions(const QuadMesh& mesh, G1Basis& basis) {
  const FunctionsByOwner by(mesh, basis);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const std::vector<int>& ids = by.vertex[v];
    if (ids.empty()) continue;
    std::vector<int> others;
    for (int e : std::set<int>(mesh.ring(v).edges.begin(), mesh.ring(v).edges.end()))
      others.insert(others.end(), by.edge[e].begin(), by.edge[e].end());
    LocalColumns cols;
    cols.add(g1_corner_unknown(mesh.ring(v).faces[0], mesh.ring(v).corners[0], 0, 0, basis.k, basis.r));  // row 0
    add_columns(basis, ids, cols);
    add_columns(basis, others, cols);
    Eigen::MatrixXd X = dense_columns(basis, ids, cols);
    const Eigen::VectorXd before = X.colwise().norm();
    project_out(X, dense_columns(basis, others, cols));
    // A vertex function within 1e-6 (relative) of its edges' functions: the basis is
    // numerically dependent there, and what is left after the projection is rounding noise
    // scaled up (measured before null_space refined its vectors: symmetric_c1 data on the split
    // pentagonal prism at 3 subdivisions, 3.3e-10, residual 3.6e-6 and a wrong solution; that
    // level is now C1 and converges). Every shipped case stays above 0.16 at every level.
    for (Eigen::Index i = 0; i < X.cols(); ++i)
      if (const double distance = X.col(i).norm() / before(i); distance < 1e-6) {
        char what[64];
        std::snprintf(what, sizeof what, "%.1e", distance);
        throw std::runtime_error("vertex " + std::to_string(v + 1) + ": one of its G1 vertex functions lies within " +
                                 what + " (relative) of its edges' functions, so the basis is numerically dependent "
                                 "there and a solution on it would be unreliable; use exact data (gluing = "
                                 "\"analysis_suitable\") or fewer subdivisions");
      }
    X = value_first_orthogonal(X);
    for (size_t i = 0; i < ids.size(); ++i) store_column(basis, ids[i], X.col(static_cast<Eigen::Index>(i)), cols);
  }
}

// A vertex-pair function plus any vertex function of its edge's ends or edge function around
// them is as good a vertex-pair function: keep the part orthogonal to those (coefficient
// space). Without this the exact echelon-form solutions can lie close to the span of the
// others, and the stiffness matrix is needlessly ill-conditioned (condition 6e7 instead of
// 1.8e3 at two subdivisions of the three-quad mesh).
void tidy_pair_functions(const QuadMesh& mesh, G1Basis& basis) {
  const FunctionsByOwner by(mesh, basis);
  for (const int j : by.pairs) {
    const auto& E = mesh.edge(basis.functions[j].owner);
    std::set<int> around;
    for (const int v : {E.v[0], E.v[1]}) {
      around.insert(by.vertex[v].begin(), by.vertex[v].end());
      for (int e : mesh.ring(v).edges) around.insert(by.edge[e].begin(), by.edge[e].end());
    }
    const std::vector<int> others(around.begin(), around.end()), self{j};
    LocalColumns cols;
    add_columns(basis, self, cols);
    add_columns(basis, others, cols);
    Eigen::MatrixXd x = dense_columns(basis, self, cols);
    project_out(x, dense_columns(basis, others, cols));
    store_column(basis, j, x.col(0), cols);
  }
}

// At a boundary vertex, the traces on the boundary of its vertex (and vertex-pair) functions
// can be linearly dependent (e.g. where the boundary is straight). Dirichlet data are
// imposed on the traces, so each group is changed, within its span, into functions with
// independent traces and functions with zero trace (column-pivoted QR of the trace rows).
void separate_boundary_traces(const QuadMesh& mesh, G1Basis& basis) {
  const int k = basis.k, r = basis.r, n = 2 * k - r + 1;
  std::set<long> trace_unknowns;  // row 0 of every boundary side
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (!E.boundary()) continue;
    for (int a = 0; a < n; ++a) trace_unknowns.insert(g1_corner_unknown(E.face[0], E.corner[0], a, 0, k, r));
  }
  std::map<int, std::vector<int>> groups;  // boundary vertex -> functions
  for (size_t j = 0; j < basis.functions.size(); ++j) {
    const auto& f = basis.functions[j];
    int v = -1;
    if (f.kind == G1BasisFunction::Kind::vertex) v = f.owner;
    if (f.kind == G1BasisFunction::Kind::vertex_pair) {
      const auto& E = mesh.edge(f.owner);
      v = mesh.boundary_vertex(E.v[0]) ? E.v[0] : E.v[1];
    }
    if (v >= 0 && mesh.boundary_vertex(v)) groups[v].push_back(static_cast<int>(j));
  }
  for (const auto& [v, ids] : groups) {
    LocalColumns cols;
    add_columns(basis, ids, cols);
    const Eigen::MatrixXd X = dense_columns(basis, ids, cols);
    std::vector<int> trace_rows;
    for (int row = 0; row < cols.size(); ++row)
      if (trace_unknowns.count(cols.global[row])) trace_rows.push_back(row);
    if (trace_rows.empty()) continue;
    const Eigen::MatrixXd T = X(trace_rows, Eigen::all);
    const Eigen::Index m = X.cols();
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(T);
    qr.setThreshold(1e-10);
    const Eigen::Index rank = qr.rank();
    if (rank == m) continue;
    // T P = Q [R11 R12]: the columns P [-R11^{-1} R12; I] have zero trace.
    const Eigen::MatrixXd R = qr.matrixR().topRows(rank).template triangularView<Eigen::Upper>();
    const Eigen::MatrixXd W = R.leftCols(rank).template triangularView<Eigen::Upper>().solve(R.rightCols(m - rank));
    Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(m, m - rank);
    const auto& P = qr.colsPermutation().indices();
    for (Eigen::Index c = 0; c < m - rank; ++c) {
      Z(P(rank + c), c) = 1;
      for (Eigen::Index i = 0; i < rank; ++i) Z(P(i), c) = -W(i, c);
    }
    const Eigen::MatrixXd Y = X * Z;
    // Exactly zero on the boundary rows (rounding there would make the trace nonzero).
    for (Eigen::Index c = 0; c < m - rank; ++c) store_column(basis, ids[P(rank + c)], Y.col(c), cols, &trace_unknowns);
  }
}

// The constant function's coefficients in the basis: the least-squares solution of B c = 1,
// B the functions' B-spline coefficients (each face's split splines are a partition of unity,
// so the constant is all ones there); CGLS on B, whose condition is that of the mass matrix's
// square root (about 60). With rational data the constant is in the span to rounding; with
// floating-point data only to their SVD tolerance (residual 2.3e-9 measured on geometric data
// of 17-digit coordinates). Either is enough: c only steers the changes of basis below, which
// keep every span whatever c is (the tests check the constant's reproduction separately).
Eigen::VectorXd constant_coefficients(const G1Basis& basis) {
  std::vector<Eigen::Triplet<double>> entries;
  for (size_t j = 0; j < basis.functions.size(); ++j)
    for (const auto& [c, x] : basis.functions[j].coefficients)
      entries.emplace_back(static_cast<int>(c), static_cast<int>(j), x);
  Eigen::SparseMatrix<double> B(static_cast<Eigen::Index>(basis.unknowns()),
                                static_cast<Eigen::Index>(basis.functions.size()));
  B.setFromTriplets(entries.begin(), entries.end());
  Eigen::LeastSquaresConjugateGradient<Eigen::SparseMatrix<double>> cgls(B);
  cgls.setTolerance(1e-15);
  cgls.setMaxIterations(20000);
  return cgls.solve(Eigen::VectorXd::Ones(B.rows()));
}

// Changes of basis within the functions of each interior vertex and each interior edge after
// which the constant function's coefficients are 1 on all of them (they are 1 on the face
// functions already). Classical AMG takes the all-ones vector as the near-null space of the
// matrix. In the orthonormalized basis the constant's coefficients were anything from -1.6 to
// 2.3, and BoomerAMG-CG's iterations grew with h (g1_mixed_valences: 35, 41, 48, 70, 125 over
// five levels, the C0 space 46-50); with this change 33, 38, 41, 41, 49 (docs/SOLVERS.md).
// With Q an orthonormal basis of a group's span and g = Q a the constant's part there, the new
// functions are Q R with R = |a|/sqrt(m) H, H the reflection taking 1/sqrt(m) to a/|a|, so
// that R 1 = a: orthogonal up to one common factor, so the conditioning is kept. At a vertex
// this is done to the functions that vanish there, and the value function is scaled by its
// coefficient, so it stays first, with value 1 at the vertex. Boundary groups are left as
// separate_boundary_traces made them: Dirichlet data take them, or the boundary breaks the
// near-null space anyway.
void constant_carrying_functions(const QuadMesh& mesh, G1Basis& basis) {
  const Eigen::VectorXd c = constant_coefficients(basis);
  const FunctionsByOwner by(mesh, basis);
  auto carry = [&](const std::vector<int>& ids) {
    const Eigen::Index m = static_cast<Eigen::Index>(ids.size());
    if (m < 2) return;
    LocalColumns cols;
    add_columns(basis, ids, cols);
    const Eigen::MatrixXd X = dense_columns(basis, ids, cols);
    Eigen::VectorXd cg(m);
    for (Eigen::Index i = 0; i < m; ++i) cg(i) = c(ids[static_cast<size_t>(i)]);
    const Eigen::MatrixXd Q = orthonormal_columns(X);
    const Eigen::VectorXd a = Q.transpose() * (X * cg);
    const double size = a.norm();
    // A group where the constant has (almost) no part is left orthonormal: scaled to carry
    // it, its functions would be tiny (on the prism sphere's 10 skewed crossings the part is
    // 0.003 of the functions' size, elsewhere 0.38 or more), and a zero-mean solve that pins
    // one of them nearly singular (condition 1.5e8 instead of 8e2 at level 0).
    if (!(size / std::sqrt(double(m)) > 0.1 * X.colwise().norm().maxCoeff())) return;
    Eigen::VectorXd w = Eigen::VectorXd::Constant(m, 1 / std::sqrt(double(m))) - a / size;
    Eigen::MatrixXd R = Eigen::MatrixXd::Identity(m, m);
    if (w.norm() > 1e-14) {
      w.normalize();
      R -= 2 * w * w.transpose();
    }
    const Eigen::MatrixXd Y = Q * (R * (size / std::sqrt(double(m))));
    for (Eigen::Index i = 0; i < m; ++i) store_column(basis, ids[static_cast<size_t>(i)], Y.col(i), cols);
  };
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const std::vector<int>& ids = by.vertex[v];
    if (ids.empty() || mesh.boundary_vertex(v)) continue;
    // The value function (first, value_first_orthogonal): c0 = 1 / its value at the vertex,
    // at least 1 after the scaling to largest coefficient 1. The same cut as for the groups
    // keeps a vertex whose value lies with its vertex-pair functions from being scaled to ~0.
    const double c0 = c(ids[0]);
    if (std::abs(c0) > 0.1)
      for (auto& [u, x] : basis.functions[ids[0]].coefficients) x *= c0;
    carry(std::vector<int>(ids.begin() + 1, ids.end()));
  }
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (!mesh.edge(e).boundary()) carry(by.edge[e]);
}

// Floating-point data refused when the local SVDs' margin is below kMinG1RankMargin.
void check_rank_margin(const G1SpaceDimension& d) {
  if (d.smallest_kept >= kMinG1RankMargin * d.largest_dropped) return;
  char line[520];
  std::snprintf(line, sizeof line,
                "the numerical rank of the G1 conditions is not clear-cut for these floating-point gluing data: "
                "singular values counted as nonzero go down to %.2g of their matrix's largest, those counted as zero "
                "up to %.2g (a factor %.0f apart is required), so floating point cannot decide the space's dimension; "
                "use rational data (analysis_suitable, or a gluing file), or fewer subdivisions (such data lose numerical "
                "rank as they are restricted to shorter edges)",
                d.smallest_kept, d.largest_dropped, kMinG1RankMargin);
  throw std::runtime_error(line);
}

}  // namespace

void check_g1_construction_size(long faces, int k, int r) {
  const long n = 2L * k - r + 1, unknowns = faces * n * n;
  if (unknowns <= kMaxG1Unknowns) return;
  char estimate[120];
  std::snprintf(estimate, sizeof estimate, "about %.0f GB and %.0f s or more here", 6.8 * double(unknowns) / 1769472,
                25.0 * double(unknowns) / 1769472);
  throw std::length_error(std::to_string(faces) + " faces of degree " + std::to_string(k) + " are " +
                          std::to_string(unknowns) + " unknowns, more than the " + std::to_string(kMaxG1Unknowns) +
                          " a G1 space is built for here (" + estimate + ")");
}

G1Basis g1_basis(const QuadMesh& mesh, const GluingData& gluing, int k, int r, bool floating,
                 const std::function<void(const std::string&)>& progress) {
  auto say = [&](const std::string& s) {
    if (progress) progress("G1 basis: " + s);
  };
  G1Basis basis;
  basis.k = k;
  basis.r = r;
  basis.exact = gluing.exact() && !floating;
  // Sums of cosines (valences 5, 7, 8 with the symmetric data): exact data, floating-point
  // local functions, the dimension modulo primes with roots of unity (sparse, not an SVD).
  const bool cyclotomic = !basis.exact && !floating && gluing.algebraic();
  say(std::string("dimension (rank of the C1 conditions, ") +
      (basis.exact ? "exact" : cyclotomic ? "modulo primes with roots of unity" : "floating point, local SVDs") + ", " +
      std::to_string(long(mesh.num_faces()) * (2 * k - r + 1) * (2 * k - r + 1)) + " unknowns)");
  if (basis.exact) {
    check_g1_arguments(mesh, gluing, k, r);
    std::vector<G1ExactRows> rows = g1_condition_rows_per_edge(mesh, gluing, k, r);
    long constraints = 0;
    for (const auto& x : rows) constraints += static_cast<long>(x.size());
    auto echelons = eliminate_strips(mesh, rows, k, r);
    basis.space = dimension_from_strips(mesh, k, r, echelons, constraints);
    say("local functions at " + std::to_string(mesh.num_vertices()) + " vertices and " +
        std::to_string(mesh.num_edges()) + " edges");
    build<mpq_class>(mesh, gluing, basis, say, std::move(rows), std::move(echelons));
  } else {
    basis.space = cyclotomic ? g1_space_dimension_cyclotomic(mesh, gluing, k, r)
                             : g1_space_dimension_local(mesh, gluing, k, r);  // both validate k, r, gluing
    if (basis.space.local) check_rank_margin(basis.space);
    say("local functions at " + std::to_string(mesh.num_vertices()) + " vertices and " +
        std::to_string(mesh.num_edges()) + " edges");
    build<long double>(mesh, gluing, basis, say);
  }
  say("tidying " + std::to_string(basis.functions.size()) + " functions");
  tidy_edge_functions(mesh, basis);
  tidy_vertex_functions(mesh, basis);
  tidy_pair_functions(mesh, basis);
  separate_boundary_traces(mesh, basis);
  // Largest coefficient +1: comparable scales for assembly and plots, a definite sign.
  for (size_t n = 0; n < basis.functions.size(); ++n) {
    auto& f = basis.functions[n];
    double largest = 0;
    for (const auto& [c, v] : f.coefficients)
      if (std::abs(v) > std::abs(largest)) largest = v;
    if (!(std::abs(largest) > 0) || !std::isfinite(largest))
      throw std::runtime_error("the G1 construction produced function " + std::to_string(n) +
                               " with no nonzero (or a non-finite) coefficient; these gluing data break it");
    for (auto& [c, v] : f.coefficients) v /= largest;
  }
  say("the constant's coefficients");
  constant_carrying_functions(mesh, basis);
  for (const auto& f : basis.functions) ++basis.counts[static_cast<int>(f.kind)];
  const long count = static_cast<long>(basis.functions.size());
  if (count != basis.space.dimension)
    throw std::runtime_error("the basis has " + std::to_string(count) + " functions but dim S_" + std::to_string(k) +
                             "^{1," + std::to_string(r) + "} = " + std::to_string(basis.space.dimension) +
                             " (the rank tolerance does not separate these gluing data)");
  return basis;
}

std::vector<int> g1_inseparable_edges(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  std::vector<int> out;
  const bool exact = gluing.exact();
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    // Corner blocks at v[0] first, then at v[1], then the strips.
    LocalColumns cols;
    add_corner_block(cols, E.face[0], E.corner[0], k, r);
    add_corner_block(cols, E.face[1], (E.corner[1] + 1) % 4, k, r);
    add_corner_block(cols, E.face[0], (E.corner[0] + 1) % 4, k, r);
    add_corner_block(cols, E.face[1], E.corner[1], k, r);
    add_edge_strips(cols, mesh, e, k, r);
    bool separable;
    if (exact) {
      const auto Z = null_space_exact(restrict_rows(g1_condition_rows_exact(mesh, gluing, k, r, e), cols), cols.size());
      // Rank of the Taylor rows [from, to) of the null-space vectors, exactly.
      auto rank = [&](int from, int to) {
        std::vector<std::vector<mpq_class>> T(to - from, std::vector<mpq_class>(Z.size()));
        for (size_t j = 0; j < Z.size(); ++j)
          for (int i = from; i < to; ++i) T[i - from][j] = Z[j][i];
        long r = 0;
        null_space_exact(std::move(T), static_cast<int>(Z.size()), &r);
        return r;
      };
      separable = rank(0, 16) == rank(0, 8) + rank(8, 16);
    } else {
      const Eigen::MatrixXd Z = null_space(restrict_rows(g1_condition_rows_long(mesh, gluing, k, r, e), cols), cols.size());
      auto rank = [&](int from, int to) {
        Eigen::JacobiSVD<Eigen::MatrixXd> svd(Z.middleRows(from, to - from));
        svd.setThreshold(kTolerance);
        return static_cast<long>(svd.rank());
      };
      separable = rank(0, 16) == rank(0, 8) + rank(8, 16);
    }
    if (!separable) out.push_back(e);
  }
  return out;
}

}  // namespace knotwork
