#include <chrono>
#include <cstdio>

#include "app/commands.hpp"
#include "cases/json_output.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"

namespace knotwork {

int dimension_command(const DimensionOptions& o) {
  const PartitionDescription p = load_partition(o.file);
  const RectangularPartition partition(p.cells);
  const auto t0 = std::chrono::steady_clock::now();
  const DimensionResult r =
      spline_space_dimension(partition, p.m, p.n, p.alpha, p.beta, o.exact ? RankMethod::kExact : RankMethod::kModular);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PartitionTopology topo = partition_topology(partition);
  using K = PartitionTopology::KnotKind;
  // Weller's Prop. 4.2 count applies to C^{d-1} splines of equal bi-degree d.
  const bool weller_applies = p.m == p.n && p.alpha == p.m - 1 && p.beta == p.n - 1;
  const long weller = weller_applies ? weller_dimension_formula(topo, p.m) : 0;
  const std::vector<std::string> hypotheses = weller_applies ? weller_hypotheses_violations(topo, p.m)
                                                             : std::vector<std::string>{};
  // The smoothing cofactor count and the diagonalizable-mesh formula are for highest smoothness.
  const bool highest = p.alpha == p.m - 1 && p.beta == p.n - 1;
  const ConformalityCount cofactor = highest ? conformality_count(topo, p.m, p.n) : ConformalityCount{};
  if (o.json) {
    Json j = Json::object();
    j.set("file", o.file).set("cells", partition.num_cells())
        .set("degree", Json::array().push(double(p.m)).push(double(p.n)))
        .set("smoothness", Json::array().push(double(p.alpha)).push(double(p.beta)))
        .set("unknowns", r.unknowns).set("constraints", r.constraints).set("rank", r.rank)
        .set("dimension_bruteforce", r.dimension).set("exact", r.exact ? "rational" : "two primes")
        .set("seconds", seconds).set("vertices", static_cast<int>(topo.vertices.size()))
        .set("interior_vertices", topo.interior_vertices()).set("t_nodes", topo.t_nodes())
        .set("crossings", topo.crossings()).set("interior_edges", topo.interior_edges())
        .set("knot_lines", topo.count(K::kLine)).set("knot_rays", topo.count(K::kRay))
        .set("knot_segments", topo.count(K::kSegment)).set("vanished_segments", topo.vanished_segments(p.m, p.n));
    if (weller_applies) {
      j.set("weller_prop_4_2", weller).set("weller_hypotheses_failed", Json::strings(hypotheses));
    } else {
      j.set_null("weller_prop_4_2");
    }
    if (highest) {
      j.set("dimension_cofactor", cofactor.dimension).set("conformality_rows", cofactor.conformality_rows)
          .set("conformality_rank", cofactor.conformality_rank).set_bool("diagonalizable", cofactor.diagonalizable);
      if (cofactor.formula) j.set("dimension_formula", *cofactor.formula); else j.set_null("dimension_formula");
    } else {
      j.set_null("dimension_cofactor").set_null("diagonalizable").set_null("dimension_formula");
    }
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
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
