#pragma once
// The dimension study of a T-mesh (`knotwork dimension`): brute force, topology, and the
// formulas that apply.
#include <string>
#include <vector>

#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/rectangular_partition.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"
#include "cases/json_output.hpp"

namespace knotwork {

// Everything `knotwork dimension` computes for one partition.
struct DimensionStudy {
  explicit DimensionStudy(const PartitionDescription& description) : p(description), partition(description.cells) {}
  PartitionDescription p;
  RectangularPartition partition;
  DimensionResult r;
  double seconds = 0;
  PartitionTopology topo;
  bool weller_applies = false, highest = false;
  long weller = 0;
  std::vector<std::string> hypotheses;
  ConformalityCount cofactor;
};

// Throws InputError (naming `name`) when the brute force would be too large.
DimensionStudy dimension_study(const PartitionDescription& p, const std::string& name, bool exact);
// `knotwork dimension --json`'s object; `file` stands for the partition's file.
Json dimension_json(const std::string& file, const DimensionStudy& d);

}  // namespace knotwork
