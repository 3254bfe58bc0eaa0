// The dimension of a G1 space with floating-point gluing data from local SVDs, linear in the
// mesh. Written here because the global alternatives do not fit: a dense SVD of all the
// conditions is cubic (10 000 unknowns took minutes), and a sparse QR's rank (SuiteSparseQR)
// is a heuristic on column norms, not a singular-value criterion. The structure of the
// conditions makes local SVDs exact in exact arithmetic: an edge's strips occur in its own
// rows only (docs/G1.md), so the rank of the whole system is the sum of every edge's strip
// rank and the rank of the rows left on the corner blocks; those rows touch the corner blocks
// at the edge's two ends, and split between the two vertices wherever the edge is separable.
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

#include "basis/g1/g1_space.hpp"

namespace knotwork {

namespace {

constexpr double kRelativeTolerance = 1e-10;

// Singular values relative to their matrix's scale: the smallest counted as nonzero and the
// largest counted as zero, over every local SVD (the margin the tolerance has).
struct RankGap {
  double smallest_kept = std::numeric_limits<double>::infinity(), largest_dropped = 0;
  void merge(const RankGap& o) {
    smallest_kept = std::min(smallest_kept, o.smallest_kept);
    largest_dropped = std::max(largest_dropped, o.largest_dropped);
  }
};

long count_above(const Eigen::VectorXd& singular_values, double scale, RankGap& gap) {
  if (!singular_values.allFinite() || !std::isfinite(scale))
    throw std::runtime_error("a singular value of the G1 conditions is not finite (these gluing data are not finite)");
  long n = 0;
  for (Eigen::Index i = 0; i < singular_values.size(); ++i) {
    const double relative = singular_values(i) / scale;
    if (relative > kRelativeTolerance) {
      ++n;
      gap.smallest_kept = std::min(gap.smallest_kept, relative);
    } else {
      gap.largest_dropped = std::max(gap.largest_dropped, relative);
    }
  }
  return n;
}

// The numbers of one edge's elimination (shared by edges whose systems are equal entry for
// entry: after a subdivision, most inner edges of a coarse face).
struct EdgeReduction {
  long strip_rank = 0;
  double scale = 0;                 // largest singular value of the edge's rows (unit rows)
  Eigen::MatrixXd rows[2];          // rows on the corner blocks at v[0] alone and at v[1] alone
  Eigen::MatrixXd coupled;          // rows on both, v[0]'s columns first (an inseparable edge)
  RankGap gap;
};

// S: the rows on the edge's strips, K: on the corner blocks, the n0 at v[0] first.
EdgeReduction reduce(const Eigen::MatrixXd& S, const Eigen::MatrixXd& K, Eigen::Index n0) {
  EdgeReduction out;
  const Eigen::Index m = S.rows(), n1 = K.cols() - n0;
  Eigen::MatrixXd whole(m, S.cols() + K.cols());
  whole << S, K;
  out.scale = Eigen::JacobiSVD<Eigen::MatrixXd>(whole).singularValues()(0);
  // S = U diag(s) V^T: the rows U^T [S K] beyond the strip rank are zero on the strips.
  const Eigen::JacobiSVD<Eigen::MatrixXd> strips(S, Eigen::ComputeFullU);
  out.strip_rank = count_above(strips.singularValues(), out.scale, out.gap);
  const Eigen::MatrixXd R = strips.matrixU().rightCols(m - out.strip_rank).transpose() * K;
  if (R.rows() == 0) return out;
  // A basis of R's row space, scaled by its singular values.
  const Eigen::JacobiSVD<Eigen::MatrixXd> remainder(R, Eigen::ComputeThinV);
  const long rank = count_above(remainder.singularValues(), out.scale, out.gap);
  if (rank == 0) return out;
  const Eigen::MatrixXd W =
      remainder.singularValues().head(rank).asDiagonal() * remainder.matrixV().leftCols(rank).transpose();
  // The row space splits between the two ends when rank = rank(W on v[0]) + rank(W on v[1]);
  // then the combinations that vanish on one end's columns are rows of the other end alone.
  const Eigen::MatrixXd W0 = W.leftCols(n0), W1 = W.rightCols(n1);
  const Eigen::JacobiSVD<Eigen::MatrixXd> s0(W0, Eigen::ComputeFullU), s1(W1, Eigen::ComputeFullU);
  const long r0 = n0 ? count_above(s0.singularValues(), out.scale, out.gap) : 0;
  const long r1 = n1 ? count_above(s1.singularValues(), out.scale, out.gap) : 0;
  if (r0 + r1 == rank) {
    out.rows[0] = n1 ? Eigen::MatrixXd(s1.matrixU().rightCols(rank - r1).transpose() * W0) : W0;
    out.rows[1] = n0 ? Eigen::MatrixXd(s0.matrixU().rightCols(rank - r0).transpose() * W1) : W1;
  } else {
    out.coupled = W;
  }
  return out;
}

// One interior edge after its strips are eliminated.
struct EdgeRemainder {
  long conditions = 0;              // the edge's rows
  std::vector<long> corner[2];      // corner-block unknowns at v[0] and at v[1]
  std::shared_ptr<const EdgeReduction> reduction;
};

using ReductionCache = std::map<std::vector<double>, std::shared_ptr<const EdgeReduction>>;

EdgeRemainder eliminate_edge(const QuadMesh& mesh, const GluingData& gluing, int k, int r, int e,
                             const std::vector<int>& vertex_of, ReductionCache& cache, std::mutex& mutex) {
  const auto& E = mesh.edge(e);
  const auto rows = g1_condition_rows(mesh, gluing, k, r, e);
  EdgeRemainder out;
  out.conditions = static_cast<long>(rows.size());
  std::vector<long> strip;
  for (const auto& row : rows)
    for (const auto& [c, value] : row) {
      const int v = vertex_of[c];
      if (v < 0)
        strip.push_back(c);
      else if (v == E.v[0] || v == E.v[1])
        out.corner[v == E.v[0] ? 0 : 1].push_back(c);
      else
        throw std::logic_error("G1 dimension: the rows of an edge meet a corner block of a third vertex");
    }
  for (auto* list : {&strip, &out.corner[0], &out.corner[1]}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  const Eigen::Index m = static_cast<Eigen::Index>(rows.size()), ns = static_cast<Eigen::Index>(strip.size());
  const Eigen::Index n0 = static_cast<Eigen::Index>(out.corner[0].size()), n1 = static_cast<Eigen::Index>(out.corner[1].size());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(m, ns), K = Eigen::MatrixXd::Zero(m, n0 + n1);
  auto position = [](const std::vector<long>& list, long c) {
    return static_cast<Eigen::Index>(std::lower_bound(list.begin(), list.end(), c) - list.begin());
  };
  for (Eigen::Index i = 0; i < m; ++i) {
    for (const auto& [c, value] : rows[i]) {
      const int v = vertex_of[c];
      if (v < 0)
        S(i, position(strip, c)) += value;
      else if (v == E.v[0])
        K(i, position(out.corner[0], c)) += value;
      else
        K(i, n0 + position(out.corner[1], c)) += value;
    }
    // Unit rows: each condition weighs the same whatever the size of the data at its point.
    const double norm = std::sqrt(S.row(i).squaredNorm() + K.row(i).squaredNorm());
    if (norm > 0) {
      S.row(i) /= norm;
      K.row(i) /= norm;
    }
  }
  std::vector<double> key{double(m), double(ns), double(n0), double(n1)};
  key.insert(key.end(), S.data(), S.data() + S.size());
  key.insert(key.end(), K.data(), K.data() + K.size());
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) {
      out.reduction = it->second;
      return out;
    }
  }
  auto reduction = std::make_shared<const EdgeReduction>(reduce(S, K, n0));
  const std::lock_guard<std::mutex> lock(mutex);
  out.reduction = cache.emplace(std::move(key), std::move(reduction)).first->second;
  return out;
}

int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

G1SpaceDimension g1_space_dimension_local(const QuadMesh& mesh, const GluingData& gluing, int k, int r) {
  check_g1_arguments(mesh, gluing, k, r);
  G1SpaceDimension d;
  const long n = 2 * k - r + 1;
  d.unknowns = mesh.num_faces() * n * n;
  d.tolerance = kRelativeTolerance;
  d.local = true;
  std::vector<int> vertex_of(d.unknowns, -1);  // the vertex of a corner-block unknown
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int corner = 0; corner < 4; ++corner)
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) vertex_of[g1_corner_unknown(f, corner, a, b, k, r)] = mesh.face(f)[corner];

  std::vector<EdgeRemainder> edges(mesh.num_edges());
  std::string failure;
  ReductionCache cache;
  std::mutex cache_mutex;
#pragma omp parallel for schedule(dynamic, 8)
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if (mesh.edge(e).boundary()) continue;
    try {
      edges[e] = eliminate_edge(mesh, gluing, k, r, e, vertex_of, cache, cache_mutex);
    } catch (const std::exception& x) {
#pragma omp critical
      failure = x.what();
    }
  }
  if (!failure.empty()) throw std::runtime_error(failure);
  for (const EdgeRemainder& x : edges) d.constraints += x.conditions;

  // Vertices joined by an inseparable edge form one group; every other group is one vertex.
  std::vector<int> parent(mesh.num_vertices());
  std::iota(parent.begin(), parent.end(), 0);
  for (int e = 0; e < mesh.num_edges(); ++e)
    if (edges[e].reduction && edges[e].reduction->coupled.rows() > 0) {
      ++d.coupled_edges;
      parent[find_root(parent, mesh.edge(e).v[0])] = find_root(parent, mesh.edge(e).v[1]);
    }
  std::vector<std::vector<int>> group_edges(mesh.num_vertices());
  for (int e = 0; e < mesh.num_edges(); ++e) {
    if (mesh.edge(e).boundary()) continue;
    d.rank += edges[e].reduction->strip_rank;
    group_edges[find_root(parent, mesh.edge(e).v[0])].push_back(e);
    if (edges[e].reduction->coupled.rows() == 0 && find_root(parent, mesh.edge(e).v[1]) != find_root(parent, mesh.edge(e).v[0]))
      group_edges[find_root(parent, mesh.edge(e).v[1])].push_back(e);
  }

  std::vector<long> group_rank(mesh.num_vertices(), 0);
  RankGap group_gap;
  for (const EdgeRemainder& x : edges)
    if (x.reduction) group_gap.merge(x.reduction->gap);
#pragma omp parallel for schedule(dynamic, 8)
  for (int g = 0; g < mesh.num_vertices(); ++g) {
    if (group_edges[g].empty()) continue;
    std::vector<long> columns;
    std::vector<std::pair<const Eigen::MatrixXd*, std::vector<long>>> blocks;  // rows and their columns
    double scale = 0;
    for (int e : group_edges[g]) {
      const EdgeRemainder& edge = edges[e];
      const EdgeReduction& x = *edge.reduction;
      const int v0 = mesh.edge(e).v[0], v1 = mesh.edge(e).v[1];
      scale = std::max(scale, x.scale);
      if (x.coupled.rows() > 0) {
        std::vector<long> both = edge.corner[0];
        both.insert(both.end(), edge.corner[1].begin(), edge.corner[1].end());
        blocks.emplace_back(&x.coupled, std::move(both));
        continue;
      }
      for (int end = 0; end < 2; ++end)
        if (find_root(parent, end == 0 ? v0 : v1) == g && x.rows[end].rows() > 0) blocks.emplace_back(&x.rows[end], edge.corner[end]);
    }
    for (const auto& b : blocks) columns.insert(columns.end(), b.second.begin(), b.second.end());
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    Eigen::Index rows = 0;
    for (const auto& b : blocks) rows += b.first->rows();
    if (rows == 0) continue;
    if (static_cast<long>(columns.size()) > kMaxG1FloatingGroup) {
#pragma omp critical
      failure = std::to_string(columns.size()) + " corner-block unknowns are coupled by edges whose degree is below their "
                "separability (more than the " + std::to_string(kMaxG1FloatingGroup) +
                " the floating-point rank takes in one SVD)";
      continue;
    }
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(columns.size()));
    Eigen::Index top = 0;
    for (const auto& [block, cols] : blocks) {
      for (size_t j = 0; j < cols.size(); ++j) {
        const auto at = std::lower_bound(columns.begin(), columns.end(), cols[j]) - columns.begin();
        A.block(top, at, block->rows(), 1) = block->col(static_cast<Eigen::Index>(j));
      }
      top += block->rows();
    }
    RankGap gap;
    try {
      // JacobiSVD for a vertex's few columns (Eigen 3.4's BDCSVD returned NaN on some small
      // systems of the G1 bases; count_above refuses a NaN). Groups joined by inseparable edges
      // grow with the mesh, and there JacobiSVD is too slow (the whole dimension of the fan of 5
      // at 4 subdivisions, k = 3: 35 s, against 0.9 s): BDCSVD.
      const Eigen::VectorXd values = A.cols() <= 200 ? Eigen::VectorXd(Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues())
                                                     : Eigen::VectorXd(Eigen::BDCSVD<Eigen::MatrixXd>(A).singularValues());
      group_rank[g] = count_above(values, scale, gap);
    } catch (const std::exception& x) {
#pragma omp critical
      failure = x.what();
    }
#pragma omp critical
    group_gap.merge(gap);
  }
  if (!failure.empty()) throw std::runtime_error(failure);
  for (long x : group_rank) d.rank += x;
  d.smallest_kept = group_gap.smallest_kept;
  d.largest_dropped = group_gap.largest_dropped;
  d.dimension = d.unknowns - d.rank;
  return d;
}

}  // namespace knotwork
