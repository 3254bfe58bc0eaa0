#pragma once
#include <gmpxx.h>

#include <string>
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"

namespace knotwork {

// Vertices, edges and knots of a rectangular partition (T-mesh).
// A *knot* (Weller) or *l-edge* (PT-splines) is a maximal segment of collinear interior
// edges: a knot LINE / cross-cut has both ends on the boundary, a knot RAY one, a knot
// SEGMENT / T l-edge none. Every interior end of a knot is a T-node.
struct PartitionTopology {
  struct Vertex {
    mpq_class x, y;
    bool boundary = false;
    int valence = 0;  // incident edges: 2 (a corner of the domain), 3 (T-node), 4 (crossing)
  };
  struct Edge {
    int from, to;  // vertex indices, increasing coordinate
    bool vertical, boundary;
  };
  enum class KnotKind { kLine, kRay, kSegment };
  struct Knot {
    bool vertical;
    mpq_class position;        // x of a vertical knot, y of a horizontal one
    std::vector<int> vertices;  // in order along the knot, ends included
    KnotKind kind;
  };
  std::vector<Vertex> vertices;
  std::vector<Edge> edges;
  std::vector<Knot> knots;

  int interior_vertices() const;
  int interior_edges() const;
  int t_nodes() const;    // interior vertices of valence 3
  int crossings() const;  // interior vertices of valence 4
  int count(KnotKind kind) const;
  // T l-edges (knot segments) that carry no extra freedom in S(m, n, m-1, n-1): a horizontal
  // one with at most m+1 vertices, a vertical one with at most n+1 (docs/MATH.md §3).
  int vanished_segments(int m, int n) const;
};

PartitionTopology partition_topology(const RectangularPartition& partition);

// Weller, Prop. 4.2: (d+1)^2 + (d+1)|E_I| - (2d+1)|V_I|, the dimension of the C^{d-1}
// splines of bi-degree d over the partition WHEN it carries a semi-regular collection with
// interior multiplicities 1. Not a dimension for arbitrary T-meshes: the brute-force count is.
long weller_dimension_formula(const PartitionTopology& topology, int d);

}  // namespace knotwork

namespace knotwork {
// The hypotheses of Weller's Prop. 4.1 (interior multiplicities 1): every knot segment has at
// least d+2 vertices, and where two knots meet in an interior vertex v, one of them has at
// least d+2 vertices from each of its endpoints up to and including v (Lemma 3.4, which
// every semi-regular collection's partition satisfies). Returns the statements that fail.
std::vector<std::string> weller_hypotheses_violations(const PartitionTopology& topology, int d);
}  // namespace knotwork
