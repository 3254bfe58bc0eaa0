// T-mesh (rectangular partition) files, TOML: load_partition checks the cells tile a
// rectangle (no overlap, no gap, no empty cell), then the partition's topology — what
// `knotwork dimension` and `knotwork basis` build first — on partitions small enough to be cheap.
#include <algorithm>

#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/rectangular_partition.hpp"
#include "cases/case_file.hpp"
#include "fuzz/fuzz_input.hpp"
#include "basis/core/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = knotwork_fuzz::scratch_file(data, size, "tmesh.toml");
  knotwork::PartitionDescription p;
  try {
    p = knotwork::load_partition(path, false);
  } catch (const knotwork::InputError&) {
    return 0;
  }
  if (p.cells.size() > 256) return 0;
  try {
    const knotwork::RectangularPartition partition(p.cells);
    const knotwork::PartitionTopology topology = knotwork::partition_topology(partition);
    knotwork::weller_hypotheses_violations(topology, std::max(p.m, p.n));
    topology.vanished_segments(p.m, p.n);
  } catch (const std::invalid_argument&) {  // cells that do not tile (load_partition names the file)
  }
  return 0;
}
