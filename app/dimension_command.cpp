#include <chrono>
#include <cstdio>
#include <stdexcept>
#include "app/commands.hpp"
#include "studies/dimension_study.hpp"
#include "studies/studies.hpp"
#include "cases/json_output.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

int dimension_command(const DimensionOptions& o) {
  const DimensionStudy d = dimension_study(load_partition(o.file), o.file, o.exact);
  if (o.json) {
    std::printf("%s\n", dimension_json(o.file, d).dump().c_str());
    return 0;
  }
  using K = PartitionTopology::KnotKind;
  const PartitionDescription& p = d.p;
  const RectangularPartition& partition = d.partition;
  const DimensionResult& r = d.r;
  const double seconds = d.seconds;
  const PartitionTopology& topo = d.topo;
  const bool weller_applies = d.weller_applies, highest = d.highest;
  const long weller = d.weller;
  const std::vector<std::string>& hypotheses = d.hypotheses;
  const ConformalityCount& cofactor = d.cofactor;
  std::printf("knotwork dimension %s\n", o.file.c_str());
  std::printf("  space      S(%d, %d, %d, %d): bi-degree (%d, %d), C^%d in x, C^%d in y, %d cells\n", p.m, p.n, p.alpha,
              p.beta, p.m, p.n, p.alpha, p.beta, partition.num_cells());
  const char* method = !r.exact ? "modulo two primes, which agree"
                      : o.exact  ? "exact over Q"
                                 : "exact over Q, as the two primes disagreed";
  std::printf("  dimension  %ld = %ld unknowns - rank %ld (%ld constraints; rank %s, %.3f s)\n", r.dimension,
              r.unknowns, r.rank, r.constraints, method, seconds);
  std::printf("  topology   %zu vertices (%d interior: %d T-nodes, %d crossings), %d interior edges;\n"
              "             knots: %d lines, %d rays, %d segments (%d vanished: at most m+1 vertices if horizontal,\n"
              "             n+1 if vertical, so no extra freedom)\n",
              topo.vertices.size(), topo.interior_vertices(), topo.t_nodes(), topo.crossings(), topo.interior_edges(),
              topo.count(K::kLine), topo.count(K::kRay), topo.count(K::kSegment), topo.vanished_segments(p.m, p.n));
  if (highest) {
    std::printf("  cofactor   %ld = %ld (polynomial and cross-cuts) + %ld interior vertices - rank %ld of the %ld\n"
                "             T l-edge conformality conditions (smoothing cofactor-conformality, exact rank)\n",
                cofactor.dimension, cofactor.tensor_part, cofactor.interior_vertices, cofactor.conformality_rank,
                cofactor.conformality_rows);
    if (cofactor.formula)
      std::printf("  formula    %ld: diagonalizable (an ordering of the T l-edges keeps deg+1 vertices on each),\n"
                  "             so the dimension depends on the topology alone\n", *cofactor.formula);
    else
      std::printf("  formula    none: not diagonalizable (no ordering of the T l-edges keeps deg+1 vertices on each),\n"
                  "             the dimension may change with the coordinates\n");
  }
  if (weller_applies)
    std::printf("  Weller     (d+1)^2 + (d+1)|E_I| - (2d+1)|V_I| = %ld (Prop. 4.2: the dimension when the partition\n"
                "             carries a semi-regular collection with interior multiplicities 1)\n", weller);
  if (weller_applies && hypotheses.empty())
    std::printf("             hypotheses of Prop. 4.1 / Lemma 3.4: hold (the count is an upper bound)\n");
  for (const auto& h : hypotheses) std::printf("             hypothesis fails: %s\n", h.c_str());
  return 0;
}

}  // namespace knotwork
