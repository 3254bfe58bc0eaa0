#include "basis/tmesh/partition_topology.hpp"

#include <algorithm>
#include <map>

namespace knotwork {

int PartitionTopology::interior_vertices() const {
  return static_cast<int>(std::count_if(vertices.begin(), vertices.end(), [](const Vertex& v) { return !v.boundary; }));
}
int PartitionTopology::interior_edges() const {
  return static_cast<int>(std::count_if(edges.begin(), edges.end(), [](const Edge& e) { return !e.boundary; }));
}
int PartitionTopology::t_nodes() const {
  return static_cast<int>(std::count_if(vertices.begin(), vertices.end(),
                                        [](const Vertex& v) { return !v.boundary && v.valence == 3; }));
}
int PartitionTopology::crossings() const {
  return static_cast<int>(std::count_if(vertices.begin(), vertices.end(),
                                        [](const Vertex& v) { return !v.boundary && v.valence == 4; }));
}
int PartitionTopology::count(KnotKind kind) const {
  return static_cast<int>(std::count_if(knots.begin(), knots.end(), [&](const Knot& k) { return k.kind == kind; }));
}

int PartitionTopology::vanished_segments(int m, int n) const {
  return static_cast<int>(std::count_if(knots.begin(), knots.end(), [&](const Knot& k) {
    return k.kind == KnotKind::kSegment && static_cast<int>(k.vertices.size()) <= (k.vertical ? n : m) + 1;
  }));
}

PartitionTopology partition_topology(const RectangularPartition& partition) {
  PartitionTopology t;
  const auto& cells = partition.cells();
  mpq_class X0 = cells[0].x0, X1 = cells[0].x1, Y0 = cells[0].y0, Y1 = cells[0].y1;
  for (const auto& c : cells) {
    X0 = std::min(X0, c.x0); X1 = std::max(X1, c.x1);
    Y0 = std::min(Y0, c.y0); Y1 = std::max(Y1, c.y1);
  }
  // Vertices: the cell corners (every T-node is a corner of the cells meeting there).
  std::map<std::pair<mpq_class, mpq_class>, int> index;
  for (const auto& c : cells)
    for (const auto& p : {std::pair{c.x0, c.y0}, std::pair{c.x1, c.y0}, std::pair{c.x0, c.y1}, std::pair{c.x1, c.y1}})
      if (index.emplace(p, static_cast<int>(t.vertices.size())).second) {
        PartitionTopology::Vertex v;
        v.x = p.first;
        v.y = p.second;
        v.boundary = v.x == X0 || v.x == X1 || v.y == Y0 || v.y == Y1;
        t.vertices.push_back(v);
      }
  // Edges: consecutive vertices on one line, joined when a cell side covers the gap. The
  // sides on each line are merged into maximal covered intervals first, so the whole pass is
  // sorting (a scan of every cell per gap was quadratic: minutes at 10^4 cells).
  for (int vertical = 0; vertical < 2; ++vertical) {
    std::map<mpq_class, std::vector<std::pair<mpq_class, int>>> lines;  // position -> (coordinate along, vertex)
    for (int i = 0; i < static_cast<int>(t.vertices.size()); ++i) {
      const auto& v = t.vertices[i];
      lines[vertical ? v.x : v.y].emplace_back(vertical ? v.y : v.x, i);
    }
    std::map<mpq_class, std::vector<std::pair<mpq_class, mpq_class>>> sides;  // position -> (from, to)
    for (const auto& c : cells) {
      if (vertical) {
        sides[c.x0].emplace_back(c.y0, c.y1);
        sides[c.x1].emplace_back(c.y0, c.y1);
      } else {
        sides[c.y0].emplace_back(c.x0, c.x1);
        sides[c.y1].emplace_back(c.x0, c.x1);
      }
    }
    for (auto& line : lines) {
      // Named references, not a structured binding: clang 14 cannot capture bindings in lambdas.
      const mpq_class& position = line.first;
      auto& on_line = line.second;
      std::sort(on_line.begin(), on_line.end());
      auto& covered_by = sides[position];
      std::sort(covered_by.begin(), covered_by.end());
      std::vector<std::pair<mpq_class, mpq_class>> covered;  // disjoint, increasing
      for (const auto& s : covered_by) {
        if (!covered.empty() && s.first <= covered.back().second) covered.back().second = std::max(covered.back().second, s.second);
        else covered.push_back(s);
      }
      size_t next = 0;
      const bool boundary = vertical ? (position == X0 || position == X1) : (position == Y0 || position == Y1);
      std::vector<int> chain;  // current run of connected interior edges, as vertices
      auto close_chain = [&]() {
        if (chain.size() >= 2) {
          const bool start_b = t.vertices[chain.front()].boundary, end_b = t.vertices[chain.back()].boundary;
          t.knots.push_back({vertical != 0, position, chain,
                             start_b && end_b   ? PartitionTopology::KnotKind::kLine
                             : start_b || end_b ? PartitionTopology::KnotKind::kRay
                                                : PartitionTopology::KnotKind::kSegment});
        }
        chain.clear();
      };
      for (size_t k = 0; k + 1 < on_line.size(); ++k) {
        const mpq_class &a = on_line[k].first, &b = on_line[k + 1].first;
        while (next < covered.size() && covered[next].second <= a) ++next;
        if (next == covered.size() || !(covered[next].first <= a && b <= covered[next].second)) {
          if (!boundary) close_chain();
          continue;
        }
        t.edges.push_back({on_line[k].second, on_line[k + 1].second, vertical != 0, boundary});
        ++t.vertices[on_line[k].second].valence;
        ++t.vertices[on_line[k + 1].second].valence;
        if (boundary) continue;
        if (chain.empty()) chain.push_back(on_line[k].second);
        chain.push_back(on_line[k + 1].second);
      }
      if (!boundary) close_chain();
    }
  }
  return t;
}

long weller_dimension_formula(const PartitionTopology& t, int d) {
  return static_cast<long>(d + 1) * (d + 1) + static_cast<long>(d + 1) * t.interior_edges() -
         static_cast<long>(2 * d + 1) * t.interior_vertices();
}

}  // namespace knotwork

namespace knotwork {

std::vector<std::string> weller_hypotheses_violations(const PartitionTopology& t, int d) {
  std::vector<std::string> out;
  auto where = [&](const PartitionTopology::Knot& k) {
    const auto& a = t.vertices[k.vertices.front()];
    const auto& b = t.vertices[k.vertices.back()];
    return std::string(k.vertical ? "vertical" : "horizontal") + " knot from (" + a.x.get_str() + ", " + a.y.get_str() +
           ") to (" + b.x.get_str() + ", " + b.y.get_str() + ")";
  };
  for (const auto& k : t.knots)
    if (k.kind == PartitionTopology::KnotKind::kSegment && static_cast<int>(k.vertices.size()) < d + 2)
      out.push_back(where(k) + " is a knot segment with " + std::to_string(k.vertices.size()) +
                    " vertices, fewer than d+2 = " + std::to_string(d + 2));
  // For every interior vertex: the knots through it, and the vertex counts from their ends.
  std::vector<std::vector<std::pair<int, int>>> through(t.vertices.size());  // (knot, position)
  for (int k = 0; k < static_cast<int>(t.knots.size()); ++k)
    for (int i = 0; i < static_cast<int>(t.knots[k].vertices.size()); ++i) through[t.knots[k].vertices[i]].emplace_back(k, i);
  for (size_t v = 0; v < t.vertices.size(); ++v) {
    if (t.vertices[v].boundary || through[v].size() < 2) continue;
    // Vertices count with their multiplicity: an end on the boundary (edges of multiplicity
    // infinity, d+1 for open knot vectors) counts d+1 times, interior vertices once.
    bool ok = false;
    for (const auto& [k, i] : through[v]) {
      const auto& vs = t.knots[k].vertices;
      int before = 0, after = 0;
      for (int j = 0; j < static_cast<int>(vs.size()); ++j) {
        const int weight = t.vertices[vs[j]].boundary ? d + 1 : 1;
        if (j <= i) before += weight;
        if (j >= i) after += weight;
      }
      ok = ok || std::min(before, after) >= d + 2;
    }
    if (!ok)
      out.push_back("at (" + t.vertices[v].x.get_str() + ", " + t.vertices[v].y.get_str() +
                    ") neither knot has d+2 vertices on both sides (Lemma 3.4)");
  }
  return out;
}

}  // namespace knotwork
