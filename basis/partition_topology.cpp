#include "basis/partition_topology.hpp"

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
  // Edges: consecutive vertices on one line, joined when a cell side covers the gap.
  for (int vertical = 0; vertical < 2; ++vertical) {
    std::map<mpq_class, std::vector<std::pair<mpq_class, int>>> lines;  // position -> (coordinate along, vertex)
    for (int i = 0; i < static_cast<int>(t.vertices.size()); ++i) {
      const auto& v = t.vertices[i];
      lines[vertical ? v.x : v.y].emplace_back(vertical ? v.y : v.x, i);
    }
    for (auto& [position, on_line] : lines) {
      std::sort(on_line.begin(), on_line.end());
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
        const bool covered = std::any_of(cells.begin(), cells.end(), [&](const RationalBox& c) {
          return vertical ? ((c.x0 == position || c.x1 == position) && c.y0 <= a && b <= c.y1)
                          : ((c.y0 == position || c.y1 == position) && c.x0 <= a && b <= c.x1);
        });
        if (!covered) {
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
