#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "app/commands.hpp"
#include "app/studies.hpp"
#include "cases/json_output.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

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

DimensionStudy dimension_study(const PartitionDescription& p, const std::string& name, bool exact) {
  DimensionStudy d(p);
  const auto t0 = std::chrono::steady_clock::now();
  const RankMethod method = exact ? RankMethod::kExact : RankMethod::kModular;
  try {
    check_brute_force_size(d.partition.num_cells(), p.m, p.n, method);
  } catch (const std::length_error& e) {
    throw InputError(name + ": cells: " + e.what());
  }
  d.r = spline_space_dimension(d.partition, p.m, p.n, p.alpha, p.beta, method);
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  d.topo = partition_topology(d.partition);
  // Weller's Prop. 4.2 count applies to C^{d-1} splines of equal bi-degree d.
  d.weller_applies = p.m == p.n && p.alpha == p.m - 1 && p.beta == p.n - 1;
  if (d.weller_applies) {
    d.weller = weller_dimension_formula(d.topo, p.m);
    d.hypotheses = weller_hypotheses_violations(d.topo, p.m);
  }
  // The smoothing cofactor count and the diagonalizable-mesh formula are for highest smoothness.
  d.highest = p.alpha == p.m - 1 && p.beta == p.n - 1;
  if (d.highest) d.cofactor = conformality_count(d.topo, p.m, p.n);
  return d;
}

Json dimension_json(const std::string& file, const DimensionStudy& d) {
  using K = PartitionTopology::KnotKind;
  const PartitionDescription& p = d.p;
  const DimensionResult& r = d.r;
  const PartitionTopology& topo = d.topo;
  Json j = Json::object();
  j.set("file", file).set("cells", d.partition.num_cells())
      .set("degree", Json::array().push(double(p.m)).push(double(p.n)))
      .set("smoothness", Json::array().push(double(p.alpha)).push(double(p.beta)))
      .set("unknowns", r.unknowns).set("constraints", r.constraints).set("rank", r.rank)
      .set("dimension_bruteforce", r.dimension).set("exact", r.exact ? "rational" : "two primes")
      .set("seconds", d.seconds).set("vertices", static_cast<int>(topo.vertices.size()))
      .set("interior_vertices", topo.interior_vertices()).set("t_nodes", topo.t_nodes())
      .set("crossings", topo.crossings()).set("interior_edges", topo.interior_edges())
      .set("knot_lines", topo.count(K::kLine)).set("knot_rays", topo.count(K::kRay))
      .set("knot_segments", topo.count(K::kSegment)).set("vanished_segments", topo.vanished_segments(p.m, p.n));
  if (d.weller_applies) j.set("weller_prop_4_2", d.weller).set("weller_hypotheses_failed", Json::strings(d.hypotheses));
  else j.set_null("weller_prop_4_2");
  if (d.highest) {
    j.set("dimension_cofactor", d.cofactor.dimension).set("conformality_rows", d.cofactor.conformality_rows)
        .set("conformality_rank", d.cofactor.conformality_rank).set_bool("diagonalizable", d.cofactor.diagonalizable);
    if (d.cofactor.formula) j.set("dimension_formula", *d.cofactor.formula); else j.set_null("dimension_formula");
  } else {
    j.set_null("dimension_cofactor").set_null("diagonalizable").set_null("dimension_formula");
  }
  return j;
}

}  // namespace

Json dimension_json(const PartitionDescription& partition, const std::string& name, bool exact) {
  return dimension_json(name, dimension_study(partition, name, exact));
}

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
