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

ConformalityCount conformality_count(const PartitionTopology& t, int m, int n, const C0Lines& c0, RankMethod method) {
  using Kind = PartitionTopology::KnotKind;
  ConformalityCount c;
  c.tensor_part = static_cast<long>(m + 1) * (n + 1);
  auto on = [](const std::vector<mpq_class>& lines, const mpq_class& at) {
    return std::find(lines.begin(), lines.end(), at) != lines.end();
  };
  // Smoothness across the vertical line x (rho) and the horizontal line y (sigma).
  auto rho = [&](const mpq_class& x) { return on(c0.x, x) ? 0 : m - 1; };
  auto sigma = [&](const mpq_class& y) { return on(c0.y, y) ? 0 : n - 1; };
  // The cofactor of vertex v has bi-degree (m - rho - 1, n - sigma - 1): its coefficients are
  // columns first[v] .. first[v] + (m - rho)(n - sigma) - 1, index a + (m - rho) b.
  std::vector<long> first(t.vertices.size() + 1, 0);
  for (size_t v = 0; v < t.vertices.size(); ++v) {
    const auto& p = t.vertices[v];
    first[v + 1] = first[v] + (p.boundary ? 0 : static_cast<long>(m - rho(p.x)) * (n - sigma(p.y)));
  }
  c.interior_vertices = first.back();
  std::vector<SparseRationalRow> rows;
  for (const auto& k : t.knots) {
    // Across a vertical l-edge at x0 the jump is (x - x0)^(rho+1) A(x, y), A of bi-degree
    // (m - rho - 1, n): one spline in y per power of x (horizontal: the roles swapped).
    const int along = k.vertical ? n : m, copies = k.vertical ? m - rho(k.position) : n - sigma(k.position);
    if (k.kind == Kind::kLine) c.tensor_part += static_cast<long>(copies) * (along + 1);
    if (k.kind != Kind::kSegment) continue;
    // A T l-edge's cofactor vanishes beyond both ends: for each copy, the sum over its
    // vertices of (t - t_v)^(s_v + 1 + b) C_v,b (s_v the smoothness across the other line
    // through v, t the coordinate along the l-edge) is the zero polynomial of degree `along`.
    for (int copy = 0; copy < copies; ++copy)
      for (int j = 0; j <= along; ++j) {
        SparseRationalRow row;
        for (int v : k.vertices) {
          const auto& p = t.vertices[v];
          const int s = k.vertical ? sigma(p.y) : rho(p.x);
          const int width = m - rho(p.x);  // a runs along x
          const mpq_class& tv = k.vertical ? p.y : p.x;
          for (int b = 0; b < along - s; ++b) {
            const int e = s + 1 + b;  // coefficient of t^j in (t - t_v)^e
            if (j > e) continue;
            mpz_class binomial;
            mpz_bin_uiui(binomial.get_mpz_t(), e, j);
            mpq_class power = 1;
            for (int i = 0; i < e - j; ++i) power *= -tv;
            const long column = first[v] + (k.vertical ? copy + static_cast<long>(width) * b : b + static_cast<long>(width) * copy);
            row.terms.emplace_back(column, binomial * power);
          }
        }
        rows.push_back(std::move(row));
      }
  }
  c.conformality_rows = static_cast<long>(rows.size());
  c.conformality_rank = method == RankMethod::kExact ? rank_exact(rows, c.interior_vertices)
                                                     : rank_reliable(rows, c.interior_vertices);
  c.dimension = c.tensor_part + c.interior_vertices - c.conformality_rank;

  c.diagonalizable = diagonalizable_by_ordering(t, m, n);
  if (c.diagonalizable && c0.empty()) c.formula = c.tensor_part + c.interior_vertices - c.conformality_rows;
  return c;
}

}  // namespace knotwork
