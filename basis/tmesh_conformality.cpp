#include "basis/tmesh_conformality.hpp"

#include <algorithm>

#include "basis/sparse_rank.hpp"

namespace knotwork {

bool diagonalizable_by_ordering(const PartitionTopology& t, int m, int n) {
  using Kind = PartitionTopology::KnotKind;
  auto degree = [&](const PartitionTopology::Knot& k) { return k.vertical ? n : m; };
  std::vector<const PartitionTopology::Knot*> left;
  for (const auto& k : t.knots)
    if (k.kind == Kind::kSegment) left.push_back(&k);
  // Greedy from the end: an l-edge that keeps deg+1 vertices after losing its intersections
  // with ALL the others left can go last; removing it only helps the rest, so if no such
  // l-edge exists no ordering does.
  while (!left.empty()) {
    auto last = std::find_if(left.begin(), left.end(), [&](const PartitionTopology::Knot* k) {
      long own = 0;
      for (int v : k->vertices) {
        const bool shared = std::any_of(left.begin(), left.end(), [&](const PartitionTopology::Knot* o) {
          return o != k && std::find(o->vertices.begin(), o->vertices.end(), v) != o->vertices.end();
        });
        own += shared ? 0 : 1;
      }
      return own >= degree(*k) + 1;
    });
    if (last == left.end()) return false;
    left.erase(last);
  }
  return true;
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
