// The dimension study of a T-mesh: the spline space dimension by brute force and by formula.
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "studies/dimension_study.hpp"
#include "studies/studies.hpp"
#include "cases/json_output.hpp"
#include "basis/tmesh/partition_topology.hpp"
#include "basis/tmesh/spline_dimension.hpp"
#include "basis/tmesh/tmesh_conformality.hpp"
#include "cases/case_file.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

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

Json dimension_json(const PartitionDescription& partition, const std::string& name, bool exact) {
  return dimension_json(name, dimension_study(partition, name, exact));
}

}  // namespace knotwork
