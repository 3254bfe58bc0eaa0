#include "basis/tmesh/knot_polylines.hpp"

#include "basis/tmesh/partition_topology.hpp"

namespace knotwork {

KnotPolylines knot_polylines(const RectangularPartition& partition, const NurbsPatch& geometry,
                             const std::function<int(bool vertical, double at, double from, double to)>& multiplicity_of,
                             int samples) {
  const PartitionTopology topo = partition_topology(partition);
  KnotPolylines out;
  for (const auto& k : topo.knots) {
    const double at = k.position.get_d();
    std::vector<double> stops;
    for (int v : k.vertices) stops.push_back((k.vertical ? topo.vertices[v].y : topo.vertices[v].x).get_d());
    Eigen::MatrixX2d poly((stops.size() - 1) * samples + 1, 2);
    int row = 0;
    for (size_t e = 0; e + 1 < stops.size(); ++e)
      for (int s = 0; s < samples + (e + 2 == stops.size() ? 1 : 0); ++s) {
        const double t = stops[e] + (stops[e + 1] - stops[e]) * s / samples;
        poly.row(row++) = patch_point(geometry, k.vertical ? at : t, k.vertical ? t : at).transpose();
      }
    out.lines.push_back(poly);
    out.kind.push_back(k.kind == PartitionTopology::KnotKind::kLine ? 0 : k.kind == PartitionTopology::KnotKind::kRay ? 1 : 2);
    out.multiplicity.push_back(multiplicity_of(k.vertical, at, stops.front(), stops.back()));
  }
  return out;
}

}  // namespace knotwork
