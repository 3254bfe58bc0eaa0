#include "basis/tensor/multipatch_tensor.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "basis/core/disjoint_sets.hpp"
#include "basis/core/glue_patches.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

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

// The knots along both sides of every interface: a mismatch is named in knots, which says
// more than the traces glue_patches compares.
void check_interface_knots(const MultiPatch& domain, const std::vector<std::array<BSplineBasis1D, 2>>& bases) {
  auto patch_name = [&](int p) { return "patch " + patch_label(domain, p); };
  for (const PatchInterface& f : domain.interfaces) {
    const BSplineBasis1D& a = bases[f.a.patch][f.a.side <= 2 ? 1 : 0];
    const BSplineBasis1D& b = bases[f.b.patch][f.b.side <= 2 ? 1 : 0];
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
}

}  // namespace

MultiPatchTensorDiscretization build_multipatch_tensor(const MultiPatch& domain, const TensorSpaceOptions& options) {
  MultiPatchTensorDiscretization out;
  for (const NurbsPatch& patch : domain.patches) out.patches.push_back(build_tensor_discretization(patch, options));
  std::vector<std::array<BSplineBasis1D, 2>> bases;
  for (const TensorDiscretization& d : out.patches) bases.push_back({d.space_u, d.space_v});
  check_interface_knots(domain, bases);
  std::vector<const BezierMesh*> meshes;
  for (const TensorDiscretization& d : out.patches) meshes.push_back(&d.mesh);
  GluedPatches glued = glue_patches(domain, meshes);
  out.mesh = std::move(glued.mesh);
  out.first_cell = std::move(glued.first_cell);
  out.global_function = std::move(glued.global_function);
  return out;
}

MultiPatchNumbering number_multipatch_functions(const MultiPatch& domain, const TensorSpaceOptions& options) {
  MultiPatchNumbering out;
  std::vector<int>& first_function = out.first_function;
  for (const NurbsPatch& p : domain.patches) {
    out.bases.push_back(tensor_space_bases(p, options));
    first_function.push_back(first_function.back() + out.bases.back()[0].num_functions() * out.bases.back()[1].num_functions());
  }
  check_interface_knots(domain, out.bases);
  // A shared function where it first occurs, from the tensor numbering along the glued sides.
  DisjointSets copies(first_function.back());
  for (const PatchInterface& f : domain.interfaces) {
    const auto& a_basis = out.bases[f.a.patch];
    const auto& b_basis = out.bases[f.b.patch];
    const std::vector<int> a = side_indices(a_basis[0].num_functions(), a_basis[1].num_functions(), f.a.side);
    const std::vector<int> b = side_indices(b_basis[0].num_functions(), b_basis[1].num_functions(), f.b.side);
    const size_t n = a.size();
    for (size_t k = 0; k < n; ++k)
      copies.unite(first_function[f.a.patch] + a[k], first_function[f.b.patch] + b[f.reversed ? n - 1 - k : k]);
  }
  out.number = copies.numbering(&out.count);
  return out;
}

MultiPatchTensorPart build_multipatch_tensor_part(const MultiPatch& domain, const TensorSpaceOptions& options, int rank,
                                                  int ranks) {
  const int np = domain.num_patches();
  if (np < ranks)
    throw std::invalid_argument("the domain has " + std::to_string(np) + " patches, fewer than the " + std::to_string(ranks) +
                                " processes that share them patch by patch");
  const MultiPatchNumbering numbering = number_multipatch_functions(domain, options);
  const std::vector<int>& first_function = numbering.first_function;
  const std::vector<int>& number = numbering.number;
  const int count = numbering.count;
  std::vector<long> cells{0};
  for (const std::array<BSplineBasis1D, 2>& b : numbering.bases)
    cells.push_back(cells.back() + long(b[0].num_elements()) * b[1].num_elements());
  std::vector<int> first_number{0};  // functions first numbered in patch k: [first_number[k], first_number[k+1])
  for (int p = 0; p < np; ++p) {
    int last = first_number.back();
    for (int g = first_function[p]; g < first_function[p + 1]; ++g) last = std::max(last, number[g] + 1);
    first_number.push_back(last);
  }
  // Whole patches per rank, balanced by cells: patch k goes to the rank its middle cell falls in.
  std::vector<int> owner(np);
  for (int p = 0; p < np; ++p)
    owner[p] = std::min(ranks - 1, static_cast<int>((cells[p] + cells[p + 1]) / 2 * ranks / cells[np]));
  for (int r = 0; r < ranks; ++r)  // a rank left without a patch: equal numbers of patches instead
    if (std::find(owner.begin(), owner.end(), r) == owner.end()) {
      for (int p = 0; p < np; ++p) owner[p] = static_cast<int>(long(p) * ranks / np);
      break;
    }
  int own_from = np, own_to = 0;
  for (int p = 0; p < np; ++p)
    if (owner[p] == rank) own_from = std::min(own_from, p), own_to = p + 1;
  MultiPatchTensorPart out;
  MeshPart& part = out.part;
  part.first_owned_function = own_from < own_to ? first_number[own_from] : 0;
  part.last_owned_function = own_from < own_to ? first_number[own_to] : 0;
  part.global_functions = count;
  part.global_cells = static_cast<int>(cells[np]);
  const auto owned_function = [&](int g) { return g >= part.first_owned_function && g < part.last_owned_function; };

  // The pieces: the owned patches whole, then later patches' cells that hold owned functions.
  std::vector<char> is_local(count, 0);
  for (int p = own_from; p < np; ++p) {
    if (p >= own_to) {  // a halo patch only if it holds an owned function
      bool holds = false;
      for (int g = first_function[p]; g < first_function[p + 1] && !holds; ++g) holds = owned_function(number[g]);
      if (!holds) continue;
    }
    TensorDiscretization d = build_tensor_discretization(domain.patches[p], options);
    std::vector<int> chosen;
    for (int c = 0; c < d.mesh.num_cells(); ++c) {
      bool take = p < own_to;
      for (int f : d.mesh.functions(c)) take = take || owned_function(number[first_function[p] + f]);
      if (!take) continue;
      chosen.push_back(c);
      for (int f : d.mesh.functions(c)) is_local[number[first_function[p] + f]] = 1;
    }
    out.patch_of_piece.push_back(p);
    out.cells_of_piece.push_back(std::move(chosen));
    out.built.push_back(std::move(d));
  }
  // Local numbers in increasing global order.
  std::vector<int> local_of(count, -1);
  for (int g = 0; g < count; ++g)
    if (is_local[g]) local_of[g] = static_cast<int>(part.global_function.size()), part.global_function.push_back(g);
  is_local = {};
  const std::vector<PatchSideRef> exterior = exterior_sides(domain);
  BezierMesh& mesh = out.mesh;
  mesh.set_num_functions(static_cast<int>(part.global_function.size()));
  mesh.set_boundary_names(exterior_side_names(domain, exterior));
  Eigen::VectorXd weights(options.rational ? part.global_function.size() : 0);
  out.first_cell.push_back(0);
  std::vector<int> ids;
  for (size_t piece = 0; piece < out.built.size(); ++piece) {
    const int p = out.patch_of_piece[piece];
    const BezierMesh& m = out.built[piece].mesh;
    const auto local = [&](int f) { return local_of[number[first_function[p] + f]]; };
    if (options.rational)
      for (int f = 0; f < m.num_functions(); ++f)
        if (local(f) >= 0) weights[local(f)] = m.weights()[f];
    std::vector<int> extraction(m.num_distinct_extractions(), -1);
    const std::array<int, 4> boundary_id = boundary_ids_of_patch(exterior, p);
    for (int c : out.cells_of_piece[piece]) {
      int& e = extraction[m.extraction_id(c)];
      if (e < 0) e = mesh.add_extraction(m.pooled_extraction(m.extraction_id(c)));
      ids.clear();
      for (int f : m.functions(c)) ids.push_back(local(f));
      mesh.add_cell(domain_cell(m.cell(c), p, boundary_id), ids, e);
    }
    out.first_cell.push_back(mesh.num_cells());
    if (p < own_to) part.owned.last = mesh.num_cells();
  }
  if (options.rational) mesh.set_weights(std::move(weights));
  part.owned.first = 0;
  return out;
}

}  // namespace knotwork
