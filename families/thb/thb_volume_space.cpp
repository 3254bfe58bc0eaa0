// Family "thb" on a volume: truncated hierarchical B-splines on the hexahedra of one volume's
// parameter domain, from the tensor mesh of [space] degree and elements on the volume's knot
// spans, refined by halving marked cells in all three directions (octants), graded as on a
// patch. The geometry is the volume's NURBS map on the leaves.
#include "families/thb/thb_volume_space.hpp"

#include <cstdio>

#include "basis/core/input_error.hpp"
#include "basis/core/nurbs_volume.hpp"
#include "basis/thb/thb_hierarchy.hpp"
#include "cases/resource_limits.hpp"
#include "families/tensor/tensor_case.hpp"
#include "families/thb/thb_refine.hpp"
#include "families/tensor/tensor_volume_space.hpp"

namespace knotwork {

namespace {

struct ThbVolumeSection : VolumeSpaceSection {
  int admissibility = 2;
  std::unique_ptr<CaseSection> clone() const override { return std::make_unique<ThbVolumeSection>(*this); }
};

const ThbVolumeSection& section(const CaseDescription& c) { return family_section<ThbVolumeSection>(c); }

// Refuses, before it is built, a start (a tensor mesh of hexahedra) whose solve would not fit:
// the direct solve's estimate (THB has no structured preconditioner, so "auto" is direct), or
// CG's with --solver iterative.
void check_start_memory(const CaseDescription& c, const std::array<const DyadicKnots*, 3>& knots) {
  double cells = 1, functions = 1;
  for (const DyadicKnots* k : knots) cells *= k->base_elements(), functions *= double(k->num_functions(0));
  const std::array<int, 3>& degree = section(c).space.degree;
  std::string method;
  const double bytes = volume_solve_bytes(c, cells, functions, degree, &method);
  char what[200];
  std::snprintf(what, sizeof what, "%.3g THB hexahedra of degree %dx%dx%d (%.3g unknowns, %s)", cells, degree[0], degree[1],
                degree[2], functions, method.c_str());
  check_memory(c.path + ": [space] elements", bytes, what);
}

}  // namespace

void read_thb_volume_case(const CaseDocument& doc, CaseDescription& c, const std::vector<std::string>& keys) {
  const CaseReader& r = doc.reader;
  read_volume_geometry(doc, c);
  if (c.multivolume())
    r.fail("[geometry] file", "holds " + std::to_string(c.volume_domain.num_patches()) +
                                  " volumes: family \"thb\" works on one volume for now; family \"tensor\" glues several "
                                  "(docs/VOLUMES.md)");
  const DocumentNode& s = r.table(doc.root, "space", true);
  std::vector<std::string> valid = keys;
  valid.insert(valid.end(), {"continuity", "insert_knots_u", "insert_knots_v", "insert_knots_w", "rational"});
  r.check_keys(s, "space", valid);
  for (const char* key : {"continuity", "insert_knots_u", "insert_knots_v", "insert_knots_w"})
    if (s.get(key))
      r.fail(std::string("[space] ") + key, "not used with family = \"thb\" (new knots are C^(d-1); the volume's knots keep "
                                            "their continuity)");
  if (const DocumentNode* x = s.get("rational"))
    if (r.boolean(*x, "[space] rational")) r.fail("[space] rational", "family \"thb\" builds polynomial B-splines");
  ThbVolumeSection& t = c.section.emplace<ThbVolumeSection>();
  t.space.rational = false;
  read_volume_degree_elements(r, s, c, t.space);
  if (const DocumentNode* a = s.get("admissibility")) {
    const long m = r.integer(*a, "[space] admissibility");
    if (m != 0 && (m < 2 || m > 8))
      r.fail("[space] admissibility", "must be 0 (no grading) or a class m in 2..8, not " + std::to_string(m));
    t.admissibility = static_cast<int>(m);
  }
  read_quadrature(r, s, c, 3);
  read_patch_problem(doc, c);
}

std::unique_ptr<SplineSpace> make_thb_volume_space(const CaseDescription& c, int level) {
  const ThbVolumeSection& t = section(c);
  DyadicKnots u = volume_dyadic_knots(c.volume, t.space, 0, level), v = volume_dyadic_knots(c.volume, t.space, 1, level),
              w = volume_dyadic_knots(c.volume, t.space, 2, level);
  check_start_memory(c, {&u, &v, &w});
  ThbHierarchy h(std::move(u), std::move(v), std::move(w), t.admissibility);
  // Removed parts of the parameter box (the Fichera corner's octant): the level-0 cells inside them.
  if (!c.volume_removed_boxes.empty()) {
    std::vector<ThbCell> removed;
    for (int64_t i = 0; i < h.knots(0).elements(0); ++i)
      for (int64_t j = 0; j < h.knots(1).elements(0); ++j)
        for (int64_t k = 0; k < h.knots(2).elements(0); ++k) {
          const double middle[3] = {(h.knots(0).breakpoint(0, i) + h.knots(0).breakpoint(0, i + 1)) / 2,
                                    (h.knots(1).breakpoint(0, j) + h.knots(1).breakpoint(0, j + 1)) / 2,
                                    (h.knots(2).breakpoint(0, k) + h.knots(2).breakpoint(0, k + 1)) / 2};
          for (const std::array<double, 6>& b : c.volume_removed_boxes)
            if (middle[0] > b[0] && middle[0] < b[1] && middle[1] > b[2] && middle[1] < b[3] && middle[2] > b[4] && middle[2] < b[5]) {
              removed.push_back({0, i, j, k});
              break;
            }
        }
    h.remove_base_cells(removed);
  }
  return make_thb_space(c, std::move(h));
}

void override_thb_volume_space(CaseDescription& c, int degree, int elements) {
  override_volume_space(family_section<ThbVolumeSection>(c).space, degree, elements);
}

void check_thb_volume_levels(const CaseDescription& c, int levels) {
  const TensorVolumeOptions& s = section(c).space;
  double cells = 1;
  for (int k = 0; k < 3; ++k) cells *= double(s.elements_per_span[k] << (levels - 1)) * c.volume.bases[k].num_elements();
  if (cells > double(kMaxCaseCells)) throw InputError("--levels: the finest level would have more than 2^26 cells");
  const DyadicKnots u = volume_dyadic_knots(c.volume, s, 0, levels - 1), v = volume_dyadic_knots(c.volume, s, 1, levels - 1),
                    w = volume_dyadic_knots(c.volume, s, 2, levels - 1);
  check_start_memory(c, {&u, &v, &w});  // the finest level, before the first is solved
}

}  // namespace knotwork
