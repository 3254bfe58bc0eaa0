// Reading the [space] of one-patch families (see tensor_case.hpp).
#include "families/tensor/tensor_case.hpp"
#include "families/tensor/tensor_volume_space.hpp"

#include <cstdio>
#include <optional>
#include <sstream>

#include "cases/case_reader.hpp"
#include "cases/resource_limits.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

std::string shortest(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

TensorSpaceOptions& patch_space(CaseDescription& c) { return family_section<PatchSpaceSection>(c).space; }
const TensorSpaceOptions& patch_space(const CaseDescription& c) { return family_section<PatchSpaceSection>(c).space; }

void read_patch_degree_elements(const CaseDocument& doc, TensorSpaceOptions& s, bool elements_optional) {
  const CaseReader& r = doc.reader;
  const DocumentNode& t = r.table(doc.root, "space", true);
  const DocumentNode* d = t.get("degree");
  if (!d) r.fail("[space] degree", "missing required key");
  const auto dd = r.integer_pair(*d, "[space] degree");
  check_degree(r, dd, "[space] degree");
  s.degree = {static_cast<int>(dd[0]), static_cast<int>(dd[1])};
  const DocumentNode* e = t.get("elements");
  if (!e) {
    if (!elements_optional) r.fail("[space] elements", "missing required key");
    return;
  }
  const auto el = r.integer_pair(*e, "[space] elements");
  check_elements(r, el, "[space] elements");
  s.elements_per_span = {static_cast<int>(el[0]), static_cast<int>(el[1])};
}

const std::vector<std::string>& tensor_space_keys() {
  static const std::vector<std::string> keys{"family", "degree", "elements", "continuity", "rational", "quadrature_points",
                                             "error_quadrature_points", "boundary_quadrature_points", "insert_knots_u",
                                             "insert_knots_v"};
  return keys;
}

namespace {

// [space] of a volume: degree, elements and continuity as one integer or a list [u, v, w].
void read_tensor_volume_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  read_volume_geometry(doc, c);
  if (!c.volume_removed_boxes.empty())
    r.fail("[geometry] type", "'" + c.geometry_type + "' removes part of the volume's cells, which family \"tensor\" cannot; "
                              "family \"thb\" can (docs/VOLUMES.md)");
  const DocumentNode& s = r.table(doc.root, "space", true);
  std::vector<std::string> keys = tensor_space_keys();
  keys.push_back("insert_knots_w");
  r.check_keys(s, "space", keys);
  TensorVolumeOptions& o = c.section.emplace<VolumeSpaceSection>().space;
  static const char* const insert_keys[3] = {"insert_knots_u", "insert_knots_v", "insert_knots_w"};
  for (int d = 0; d < 3; ++d)
    if (const DocumentNode* k = s.get(insert_keys[d])) {
      const std::string field = std::string("[space] ") + insert_keys[d];
      o.extra_knots[d] = r.numbers(*k, field);
      const BSplineBasis1D& g = c.volume.bases[d];
      if (o.extra_knots[d].size() > size_t(kMaxCaseCells)) r.fail(field, "too many knots");
      for (double t : o.extra_knots[d])
        if (!(t > g.domain_begin() && t < g.domain_end()))
          r.fail(field, "knot " + shortest(t) + " is not inside the parameter domain (" + shortest(g.domain_begin()) + ", " +
                            shortest(g.domain_end()) + ")");
    }
  read_volume_degree_elements(r, s, c, o);
  if (const DocumentNode* n = s.get("continuity")) {
    const std::vector<long> continuity = r.integers(*n, "[space] continuity", 3);
    for (int k = 0; k < 3; ++k) {
      if (continuity[k] < 0 || continuity[k] > o.degree[k] - 1)
        r.fail("[space] continuity", "must be in [0, degree-1], got " + std::to_string(continuity[k]));
      o.continuity[k] = static_cast<int>(continuity[k]);
    }
  }
  if (const DocumentNode* k = s.get("rational")) o.rational = r.boolean(*k, "[space] rational");
  read_quadrature(r, s, c, 3);
  read_patch_problem(doc, c);
}

}  // namespace

void read_volume_degree_elements(const CaseReader& r, const DocumentNode& s, const CaseDescription& c, TensorVolumeOptions& o) {
  const auto triple = [&](const char* key) {
    const DocumentNode* n = s.get(key);
    if (!n) r.fail(std::string("[space] ") + key, "missing required key");
    return r.integers(*n, std::string("[space] ") + key, 3);
  };
  const std::vector<long> degree = triple("degree");
  for (long d : degree)
    if (d < 1 || d > kMaxCaseDegree) r.fail("[space] degree", "must be in [1, 10], got " + std::to_string(d));
  const std::vector<long> elements = triple("elements");
  double cells = 1;
  for (int k = 0; k < 3; ++k) {
    if (elements[k] < 1) r.fail("[space] elements", "must be >= 1, got " + std::to_string(elements[k]));
    cells *= double(elements[k]) * c.volume.bases[k].num_elements() + double(o.extra_knots[k].size());
  }
  if (cells > double(kMaxCaseCells)) r.fail("[space] elements", "too many elements (more than 2^26 cells)");
  for (int k = 0; k < 3; ++k) o.degree[k] = static_cast<int>(degree[k]), o.elements_per_span[k] = static_cast<int>(elements[k]);
}

void override_volume_space(TensorVolumeOptions& s, int degree, int elements) {
  if (degree) {
    if (degree < 1 || degree > kMaxCaseDegree) throw InputError("--degree: must be in [1, 10], got " + std::to_string(degree));
    s.degree.fill(degree);
    for (int& r : s.continuity)
      if (r > degree - 1) r = degree - 1;
  }
  if (elements) {
    if (elements < 1) throw InputError("--elements: must be >= 1, got " + std::to_string(elements));
    if (double(elements) * elements * elements > double(kMaxCaseCells))
      throw InputError("--elements: too many elements (more than 2^26 cells)");
    s.elements_per_span.fill(elements);
  }
}

void read_tensor_case(const CaseDocument& doc, CaseDescription& c) {
  const CaseReader& r = doc.reader;
  if (is_volume_geometry(doc)) return read_tensor_volume_case(doc, c);
  read_patch_geometry(doc, c, true);
  const DocumentNode& s = r.table(doc.root, "space", true);
  r.check_keys(s, "space", tensor_space_keys());
  TensorSpaceOptions& o = c.section.emplace<PatchSpaceSection>().space;
  read_patch_degree_elements(doc, o, false);
  if (const DocumentNode* k = s.get("continuity")) {
    const auto cont = r.integer_pair(*k, "[space] continuity");
    for (int i = 0; i < 2; ++i)
      if (cont[i] < 0 || cont[i] > o.degree[i] - 1)
        r.fail("[space] continuity", "must be in [0, degree-1], got " + std::to_string(cont[i]));
    o.continuity = {static_cast<int>(cont[0]), static_cast<int>(cont[1])};
  }
  if (const DocumentNode* k = s.get("rational")) o.rational = r.boolean(*k, "[space] rational");
  for (int d = 0; d < 2; ++d) {
    const std::string key = d == 0 ? "insert_knots_u" : "insert_knots_v";
    if (const DocumentNode* k = s.get(key)) {
      if (c.multipatch())
        r.fail("[space] " + key, "not used with a geometry of several patches (extra knots would break the interfaces)");
      o.extra_knots[d] = r.numbers(*k, "[space] " + key);
      const BSplineBasis1D& g = d == 0 ? c.geometry.basis_u : c.geometry.basis_v;
      for (double t : o.extra_knots[d])
        if (!(t > g.domain_begin() && t < g.domain_end()))
          r.fail("[space] " + key, "knot " + shortest(t) + " is not inside the parameter domain (" +
                                       shortest(g.domain_begin()) + ", " + shortest(g.domain_end()) + ")");
    }
  }
  read_quadrature(r, s, c);
  read_patch_problem(doc, c);
}

void override_patch_space(TensorSpaceOptions& s, int degree, int elements, const std::string& fixed_by) {
  if (degree) {
    if (!fixed_by.empty()) throw InputError("--degree: not used with [space] collection (" + fixed_by + " fixes the degree)");
    if (degree < 1 || degree > kMaxCaseDegree) throw InputError("--degree: must be in [1, 10], got " + std::to_string(degree));
    s.degree = {degree, degree};
    for (int& r : s.continuity)
      if (r > degree - 1) r = degree - 1;
  }
  if (elements) {
    if (!fixed_by.empty())
      throw InputError("--elements: not used with [space] collection (" + fixed_by + " fixes the functions)");
    if (elements < 1) throw InputError("--elements: must be >= 1, got " + std::to_string(elements));
    if (static_cast<long>(elements) * elements > kMaxCaseCells)
      throw InputError("--elements: too many elements (more than 2^26 cells)");
    s.elements_per_span = {elements, elements};
  }
}

PatchBreaks patch_breaks(const NurbsPatch& geometry, const TensorSpaceOptions& s, int direction, int level) {
  return span_breaks(direction == 0 ? geometry.basis_u : geometry.basis_v, s.degree[direction],
                     s.elements_per_span[direction], level);
}

PatchBreaks span_breaks(const BSplineBasis1D& g, int deg, int elements_per_span, int level) {
  const int per_span = elements_per_span << level;
  const auto bp = g.breakpoints();
  const auto mult = g.multiplicities();
  PatchBreaks out;
  for (size_t i = 0; i + 1 < bp.size(); ++i)
    for (int e = 0; e < per_span; ++e) {
      out.breaks.push_back(bp[i] + (bp[i + 1] - bp[i]) * e / per_span);
      if (out.breaks.size() == 1) continue;
      const int continuity = e == 0 ? std::min(g.degree() - mult[i], deg - 1) : deg - 1;
      out.interior_multiplicity.push_back(deg - continuity);
    }
  out.breaks.push_back(bp.back());
  return out;
}

DyadicKnots patch_dyadic_knots(const NurbsPatch& geometry, const TensorSpaceOptions& s, int direction, int level) {
  PatchBreaks b = patch_breaks(geometry, s, direction, level);
  return DyadicKnots(s.degree[direction], std::move(b.breaks), std::move(b.interior_multiplicity));
}

DyadicKnots volume_dyadic_knots(const NurbsVolume& volume, const TensorVolumeOptions& s, int direction, int level) {
  PatchBreaks b = span_breaks(volume.bases[direction], s.degree[direction], s.elements_per_span[direction], level);
  return DyadicKnots(s.degree[direction], std::move(b.breaks), std::move(b.interior_multiplicity));
}

std::unique_ptr<PatchGeometryMap> finish_patch_mesh(const CaseDescription& c, BezierMesh& mesh) {
  mesh.set_interfaces(interfaces_from_parameter_boxes(mesh));
  try {
    return std::make_unique<PatchGeometryMap>(mesh, c.geometry);
  } catch (const GeometryError& e) {
    throw InputError(c.path + ": [geometry]: " + e.what());
  }
}

const DocumentNode& read_dyadic_patch_start(const CaseDocument& doc, CaseDescription& c, const std::string& family,
                                            const std::vector<std::string>& keys, const std::string& knots,
                                            bool multipatch_allowed) {
  const CaseReader& r = doc.reader;
  read_patch_geometry(doc, c, multipatch_allowed);
  const DocumentNode& s = r.table(doc.root, "space", true);
  std::vector<std::string> valid = keys;
  valid.insert(valid.end(), {"continuity", "insert_knots_u", "insert_knots_v", "rational"});
  r.check_keys(s, "space", valid);
  for (const char* key : {"continuity", "insert_knots_u", "insert_knots_v"})
    if (s.get(key))
      r.fail(std::string("[space] ") + key, "not used with family = \"" + family + "\" (" + knots +
                                                "; the geometry's knots keep their continuity)");
  if (const DocumentNode* x = s.get("rational"))
    if (r.boolean(*x, "[space] rational")) r.fail("[space] rational", "family \"" + family + "\" builds polynomial B-splines");
  return s;
}

void check_dyadic_start_memory(const CaseDescription& c, const DyadicKnots& u, const DyadicKnots& v, const char* what) {
  const double cells = double(u.base_elements()) * v.base_elements();
  const double functions = double(u.num_functions(0)) * double(v.num_functions(0));
  char text[120];
  std::snprintf(text, sizeof text, "%.3g %s cells of degree %dx%d", cells, what, u.degree(), v.degree());
  check_memory(c.path + ": [space] elements", galerkin_bytes(cells, functions, u.degree(), v.degree()), text);
}

void check_refined_memory(const CaseDescription& c, double cells, const char* what) {
  if (c.is_volume()) {
    const std::array<int, 3>& degree = family_section<VolumeSpaceSection>(c).space.degree;
    char text[120];
    std::snprintf(text, sizeof text, "a refined space of %.3g %s hexahedra of degree %dx%dx%d", cells, what, degree[0],
                  degree[1], degree[2]);
    // About one function per cell, as on patches, and 4 KB per cell of the family's own tables.
    check_memory(c.path + ": [adapt]",
                 volume_solve_bytes(c, cells, cells + (degree[0] + 1) * (degree[1] + 1) * (degree[2] + 1), degree) + 4096 * cells,
                 text);
    return;
  }
  const auto [p, q] = patch_space(c).degree;
  char text[120];
  std::snprintf(text, sizeof text, "a refined space of %.3g %s cells of degree %dx%d", cells, what, p, q);
  check_memory(c.path + ": [adapt]", galerkin_bytes(cells, cells + (p + 1) * (q + 1), p, q) + 4096 * cells, text);
}

void check_uniform_levels(const TensorSpaceOptions& s, int levels) {
  const long finest = static_cast<long>(s.elements_per_span[0]) << (levels - 1);
  if (finest * (static_cast<long>(s.elements_per_span[1]) << (levels - 1)) > kMaxCaseCells)
    throw InputError("--levels: the finest level would have more than 2^26 cells");
}

}  // namespace knotwork
