// The faces two hexahedra of one volume's parameter domain share, from their parameter boxes:
// the 3D case of interfaces_from_parameter_boxes (bezier_mesh.hpp). Per plane, the faces on
// its high side go into the one spatial index (box_index.hpp) and each face on its low side
// asks it for those it overlaps, so hanging faces (a coarse face against four fine ones) come
// out as one piece per overlap.
#include <algorithm>
#include <map>
#include <vector>

#include "basis/core/bezier_mesh.hpp"
#include "basis/core/box_index.hpp"

namespace knotwork {

std::vector<CellInterface> face_interfaces_from_parameter_boxes(const BezierMesh& mesh) {
  struct Face {
    double s0, s1, t0, t1;
    int cell;
  };
  // normal direction 0 (u), 1 (v), 2 (w): the low and high sides, and the face's coordinates.
  static constexpr CellSide kLow[3] = {kSideLeft, kSideBottom, kSideFront};
  static constexpr CellSide kHigh[3] = {kSideRight, kSideTop, kSideBack};
  // Per normal direction and plane position: faces whose cell lies below the plane (its high
  // side there) and above it (its low side).
  std::map<double, std::vector<Face>> below[3], above[3];
  for (int c = 0; c < mesh.num_cells(); ++c) {
    const BezierCell& b = mesh.cell(c);
    const double lo[3] = {b.u0, b.v0, b.w0}, hi[3] = {b.u1, b.v1, b.w1};
    for (int n = 0; n < 3; ++n) {
      const int s = n == 0 ? 1 : 0, t = n == 2 ? 1 : 2;  // the face's coordinates, in the order u, v, w
      if (b.boundary[kHigh[n]] < 0) below[n][hi[n]].push_back({lo[s], hi[s], lo[t], hi[t], c});
      if (b.boundary[kLow[n]] < 0) above[n][lo[n]].push_back({lo[s], hi[s], lo[t], hi[t], c});
    }
  }
  std::vector<CellInterface> out;
  using Index = BoxIndex<double, int>;
  std::vector<int> hits;
  for (int n = 0; n < 3; ++n)
    for (const auto& [at, lows] : below[n]) {
      const auto found = above[n].find(at);
      if (found == above[n].end()) continue;
      const std::vector<Face>& highs = found->second;
      std::vector<Index::Entry> entries;
      entries.reserve(highs.size());
      for (size_t k = 0; k < highs.size(); ++k)
        entries.emplace_back(Index::box(highs[k].s0, highs[k].t0, highs[k].s1, highs[k].t1), static_cast<int>(k));
      const Index index(entries);
      for (const Face& a : lows) {
        index.intersecting(Index::box(a.s0, a.t0, a.s1, a.t1), hits);
        std::sort(hits.begin(), hits.end());  // the order of the pieces must not depend on the tree
        for (int k : hits) {
          const Face& b = highs[k];
          const double s0 = std::max(a.s0, b.s0), s1 = std::min(a.s1, b.s1);
          const double t0 = std::max(a.t0, b.t0), t1 = std::min(a.t1, b.t1);
          if (!(s1 > s0 && t1 > t0)) continue;  // touching along an edge or a corner only
          CellInterface e;
          e.cell_a = a.cell, e.side_a = kHigh[n], e.cell_b = b.cell, e.side_b = kLow[n];
          e.a_from = (s0 - a.s0) / (a.s1 - a.s0), e.a_to = (s1 - a.s0) / (a.s1 - a.s0);
          e.a_from_t = (t0 - a.t0) / (a.t1 - a.t0), e.a_to_t = (t1 - a.t0) / (a.t1 - a.t0);
          e.b_from = (s0 - b.s0) / (b.s1 - b.s0), e.b_to = (s1 - b.s0) / (b.s1 - b.s0);
          e.b_from_t = (t0 - b.t0) / (b.t1 - b.t0), e.b_to_t = (t1 - b.t0) / (b.t1 - b.t0);
          out.push_back(e);
        }
      }
    }
  return out;
}

}  // namespace knotwork
