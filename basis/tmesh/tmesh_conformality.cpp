#include "basis/tmesh/tmesh_conformality.hpp"

#include <algorithm>

#include "basis/exact/sparse_rank.hpp"

namespace knotwork {

bool diagonalizable_by_ordering(const PartitionTopology& t, int m, int n) {
  using Kind = PartitionTopology::KnotKind;
  // Greedy from the end: an l-edge that keeps deg+1 vertices after losing its intersections
  // with ALL the others left can go last; removing it only helps the rest, so if no such
  // l-edge exists no ordering does. `sharing[v]`: the T l-edges left through vertex v.
  std::vector<const PartitionTopology::Knot*> edges;
  for (const auto& k : t.knots)
    if (k.kind == Kind::kSegment) edges.push_back(&k);
  std::vector<int> sharing(t.vertices.size(), 0);
  for (const auto* k : edges)
    for (int v : k->vertices) ++sharing[v];
  auto own = [&](const PartitionTopology::Knot& k) {
    long count = 0;
    for (int v : k.vertices) count += sharing[v] == 1;
    return count;
  };
  std::vector<bool> removed(edges.size(), false);
  std::vector<std::vector<int>> edges_at(t.vertices.size());
  for (size_t e = 0; e < edges.size(); ++e)
    for (int v : edges[e]->vertices) edges_at[v].push_back(static_cast<int>(e));
  std::vector<int> ready;
  for (size_t e = 0; e < edges.size(); ++e)
    if (own(*edges[e]) >= (edges[e]->vertical ? n : m) + 1) ready.push_back(static_cast<int>(e));
  size_t left = edges.size();
  while (!ready.empty()) {
    const int e = ready.back();
    ready.pop_back();
    if (removed[e]) continue;
    removed[e] = true;
    --left;
    for (int v : edges[e]->vertices)
      if (--sharing[v] == 1)  // the one l-edge left through v gains a vertex of its own
        for (int o : edges_at[v])
          if (!removed[o] && own(*edges[o]) >= (edges[o]->vertical ? n : m) + 1) ready.push_back(o);
  }
  return left == 0;
}

ConformalityCount conformality_count(const PartitionTopology& t, int m, int n) {
  using Kind = PartitionTopology::KnotKind;
  ConformalityCount c;
  c.tensor_part = static_cast<long>(m + 1) * (n + 1);
  c.interior_vertices = t.interior_vertices();
  auto degree = [&](const PartitionTopology::Knot& k) { return k.vertical ? n : m; };
  std::vector<SparseRationalRow> rows;
  for (const auto& k : t.knots) {
    if (k.kind == Kind::kLine) c.tensor_part += degree(k) + 1;
    if (k.kind != Kind::kSegment) continue;
    std::vector<mpq_class> power(k.vertices.size(), mpq_class(1));  // t_v^j, j = 0, 1, ...
    for (int j = 0; j <= degree(k); ++j) {
      SparseRationalRow row;
      for (size_t i = 0; i < k.vertices.size(); ++i) {
        row.terms.emplace_back(k.vertices[i], power[i]);
        power[i] *= k.vertical ? t.vertices[k.vertices[i]].y : t.vertices[k.vertices[i]].x;
      }
      rows.push_back(std::move(row));
    }
  }
  c.conformality_rows = static_cast<long>(rows.size());
  c.conformality_rank = rank_exact(rows, static_cast<long>(t.vertices.size()));
  c.dimension = c.tensor_part + c.interior_vertices - c.conformality_rank;

  c.diagonalizable = diagonalizable_by_ordering(t, m, n);
  if (c.diagonalizable) c.formula = c.tensor_part + c.interior_vertices - c.conformality_rows;
  return c;
}

}  // namespace knotwork
