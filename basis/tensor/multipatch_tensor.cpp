#include "basis/tensor/multipatch_tensor.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "basis/core/glue_patches.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// The space along side 1..4 of a patch (sides 1 and 2 run along v).
const BSplineBasis1D& side_basis(const TensorDiscretization& d, int side) { return side <= 2 ? d.space_v : d.space_u; }

// The knots mapped onto [0, 1], reversed (t -> 1 - t) when asked.
std::vector<double> unit_knots(const BSplineBasis1D& b, bool reversed) {
  std::vector<double> k = b.knots();
  const double a = b.domain_begin(), length = b.domain_end() - a;
  for (double& t : k) t = (t - a) / length;
  if (reversed) {
    std::reverse(k.begin(), k.end());
    for (double& t : k) t = 1 - t;
  }
  return k;
}

std::string describe_knots(const BSplineBasis1D& b, const std::vector<double>& k) {
  std::ostringstream s;
  s << "degree " << b.degree() << ", knots [";
  for (size_t i = 0; i < k.size() && i < 12; ++i) s << (i ? " " : "") << k[i];
  if (k.size() > 12) s << " ...";
  return s.str() + "]";
}

}  // namespace

MultiPatchTensorDiscretization build_multipatch_tensor(const MultiPatch& domain, const TensorSpaceOptions& options) {
  MultiPatchTensorDiscretization out;
  for (const NurbsPatch& patch : domain.patches) out.patches.push_back(build_tensor_discretization(patch, options));
  auto patch_name = [&](int p) { return "patch " + patch_label(domain, p); };

  // The knots along both sides of every interface first: a mismatch is named in knots, which
  // says more than the traces glue_patches compares.
  for (const PatchInterface& f : domain.interfaces) {
    const BSplineBasis1D& a = side_basis(out.patches[f.a.patch], f.a.side);
    const BSplineBasis1D& b = side_basis(out.patches[f.b.patch], f.b.side);
    const std::vector<double> ka = unit_knots(a, false), kb = unit_knots(b, f.reversed);
    bool same = a.degree() == b.degree() && ka.size() == kb.size();
    for (size_t i = 0; same && i < ka.size(); ++i) same = std::abs(ka[i] - kb[i]) <= 1e-12;
    if (!same)
      throw GeometryError(f.where + ": the refined spaces of " + patch_name(f.a.patch) + " side " + std::to_string(f.a.side) +
                          " (" + describe_knots(a, ka) + ") and " + patch_name(f.b.patch) + " side " +
                          std::to_string(f.b.side) + " (" + describe_knots(b, kb) +
                          ") do not match: a conforming space needs the same degree, knot spans and elements along an "
                          "interface");
  }
  std::vector<const BezierMesh*> meshes;
  for (const TensorDiscretization& d : out.patches) meshes.push_back(&d.mesh);
  GluedPatches glued = glue_patches(domain, meshes);
  out.mesh = std::move(glued.mesh);
  out.first_cell = std::move(glued.first_cell);
  out.global_function = std::move(glued.global_function);
  return out;
}

}  // namespace knotwork
