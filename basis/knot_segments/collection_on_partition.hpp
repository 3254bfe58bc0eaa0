#pragma once
#include <optional>
#include <vector>

#include "basis/tmesh/rectangular_partition.hpp"
#include "basis/knot_segments/semi_regular_collection.hpp"

namespace knotwork {

// A semi-regular collection whose induced partition is a given T-mesh, when the refinement
// construction finds one: the tensor-product B-splines on the mesh's knot lines, then its
// rays and segments inserted as knot segments of multiplicity 1. Insertion orders tried: a
// knot after the knots its ends rest on (longest first among the ready ones), longest
// first, shortest first. Not every T-mesh carries a semi-regular collection (Weller's
// Lemma 3.4); then the construction extends segments and `reached` is false.
struct CollectionOnPartition {
  SemiRegularCollection collection;
  bool reached = false;                     // collection.partition() has exactly the given cells
  std::vector<InsertionReport> insertions;  // of the order kept (fewest extensions)
  const char* order = "";                   // which order was kept
};

// Throws std::invalid_argument if a coordinate is not representable closely enough as a
// double to keep cells apart, or a degree is < 1.
CollectionOnPartition collection_on_partition(const RectangularPartition& partition, int dx, int dy);

// The cells of two partitions compared as sets of double boxes.
bool same_cells(const RectangularPartition& a, const RectangularPartition& b);

}  // namespace knotwork
