#include <chrono>
#include <cstdio>

#include "app/commands.hpp"
#include "app/json_writer.hpp"
#include "basis/spline_dimension.hpp"
#include "cases/case_file.hpp"

namespace knotwork {

int dimension_command(const DimensionOptions& o) {
  const PartitionDescription p = load_partition(o.file);
  const RectangularPartition partition(p.cells);
  const auto t0 = std::chrono::steady_clock::now();
  const DimensionResult r =
      spline_space_dimension(partition, p.m, p.n, p.alpha, p.beta, o.exact ? RankMethod::kExact : RankMethod::kModular);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    Json j = Json::object();
    j.set("file", o.file).set("cells", partition.num_cells())
        .set("degree", Json::array().push(double(p.m)).push(double(p.n)))
        .set("smoothness", Json::array().push(double(p.alpha)).push(double(p.beta)))
        .set("unknowns", r.unknowns).set("constraints", r.constraints).set("rank", r.rank)
        .set("dimension_bruteforce", r.dimension).set("exact", r.exact ? "rational" : "two primes")
        .set("seconds", seconds);
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("knotwork dimension %s\n", o.file.c_str());
  std::printf("  space      S(%d, %d, %d, %d): bi-degree (%d, %d), C^%d in x, C^%d in y, %d cells\n", p.m, p.n, p.alpha,
              p.beta, p.m, p.n, p.alpha, p.beta, partition.num_cells());
  std::printf("  dimension  %ld = %ld unknowns - rank %ld (%ld constraints; rank %s, %.3f s)\n", r.dimension,
              r.unknowns, r.rank, r.constraints, r.exact ? "exact over Q" : "modulo two primes, which agree", seconds);
  return 0;
}

}  // namespace knotwork
