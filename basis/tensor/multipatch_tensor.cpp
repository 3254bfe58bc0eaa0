#include "basis/tensor/multipatch_tensor.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

// The space along a side, its functions in the side's direction (t increasing), and its cells.
struct SideSpace {
  const BSplineBasis1D* basis;
  std::vector<int> functions, cells;
};

SideSpace side_space(const TensorDiscretization& d, int side) {
  const int su = d.space_u.num_functions(), sv = d.space_v.num_functions();
  const int eu = d.elements_u, ev = d.elements_v;
  SideSpace s;
  const bool along_v = side <= 2;
  s.basis = along_v ? &d.space_v : &d.space_u;
  const int n = along_v ? sv : su, m = along_v ? ev : eu;
  for (int k = 0; k < n; ++k)
    s.functions.push_back(side == 1 ? su * k : side == 2 ? su - 1 + su * k : side == 3 ? k : k + su * (sv - 1));
  for (int k = 0; k < m; ++k)
    s.cells.push_back(side == 1 ? eu * k : side == 2 ? eu - 1 + eu * k : side == 3 ? k : k + eu * (ev - 1));
  return s;
}

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

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

MultiPatchTensorDiscretization build_multipatch_tensor(const MultiPatch& domain, const TensorSpaceOptions& options) {
  MultiPatchTensorDiscretization out;
  const int np = domain.num_patches();
  std::vector<int> first_function{0};
  for (const NurbsPatch& patch : domain.patches) {
    out.patches.push_back(build_tensor_discretization(patch, options));
    first_function.push_back(first_function.back() + out.patches.back().mesh.num_functions());
  }
  auto patch_name = [&](int p) { return "patch " + patch_label(domain, p); };

  // Glue: the functions of two sides of an interface, in the order both run, are one each.
  std::vector<int> parent(first_function.back());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::pair<CellInterface, std::array<int, 2>>> across;  // patch-local cells, and their patches
  for (const PatchInterface& f : domain.interfaces) {
    const TensorDiscretization& A = out.patches[f.a.patch];
    const TensorDiscretization& B = out.patches[f.b.patch];
    const SideSpace sa = side_space(A, f.a.side), sb = side_space(B, f.b.side);
    const std::vector<double> ka = unit_knots(*sa.basis, false), kb = unit_knots(*sb.basis, f.reversed);
    bool same = sa.basis->degree() == sb.basis->degree() && ka.size() == kb.size();
    for (size_t i = 0; same && i < ka.size(); ++i) same = std::abs(ka[i] - kb[i]) <= 1e-12;
    if (!same)
      throw GeometryError(f.where + ": the refined spaces of " + patch_name(f.a.patch) + " side " + std::to_string(f.a.side) +
                          " (" + describe_knots(*sa.basis, ka) + ") and " + patch_name(f.b.patch) + " side " +
                          std::to_string(f.b.side) + " (" + describe_knots(*sb.basis, kb) +
                          ") do not match: a conforming space needs the same degree, knot spans and elements along an "
                          "interface");
    const int n = static_cast<int>(sa.functions.size());
    for (int k = 0; k < n; ++k) {
      const int fa = sa.functions[k], fb = sb.functions[f.reversed ? n - 1 - k : k];
      const int ga = first_function[f.a.patch] + fa, gb = first_function[f.b.patch] + fb;
      if (options.rational) {
        const double wa = A.mesh.weights()[fa], wb = B.mesh.weights()[fb];
        if (std::abs(wa - wb) > 1e-9 * std::max(wa, wb))
          throw GeometryError(f.where + ": " + patch_name(f.a.patch) + " side " + std::to_string(f.a.side) + " and " +
                              patch_name(f.b.patch) + " side " + std::to_string(f.b.side) +
                              " have different weights: a conforming NURBS space needs the same weights on both sides");
      }
      parent[find_root(parent, ga)] = find_root(parent, gb);
    }
    // The cells along both sides, paired (patch-local numbers until the mesh is built).
    const int m = static_cast<int>(sa.cells.size());
    for (int k = 0; k < m; ++k) {
      CellInterface ci;
      ci.cell_a = sa.cells[k];
      ci.side_a = cell_side_of_patch_side(f.a.side);
      ci.cell_b = sb.cells[f.reversed ? m - 1 - k : k];
      ci.side_b = cell_side_of_patch_side(f.b.side);
      ci.b_from = f.reversed ? 1 : 0;
      ci.b_to = f.reversed ? 0 : 1;
      across.push_back({ci, {f.a.patch, f.b.patch}});
    }
  }

  // One number per class, in the order the patches' functions come.
  std::vector<int> number(parent.size(), -1), root_number(parent.size(), -1);
  int count = 0;
  for (size_t g = 0; g < parent.size(); ++g) {
    int& r = root_number[find_root(parent, static_cast<int>(g))];
    if (r < 0) r = count++;
    number[g] = r;
  }
  out.global_function.resize(np);
  for (int p = 0; p < np; ++p)
    out.global_function[p].assign(number.begin() + first_function[p], number.begin() + first_function[p + 1]);

  // Boundary ids: the exterior sides in order.
  const std::vector<PatchSideRef> exterior = exterior_sides(domain);
  std::vector<std::string> names;
  for (const PatchSideRef& s : exterior) names.push_back(side_name(domain, s));

  BezierMesh& mesh = out.mesh;
  mesh.set_num_functions(count);
  mesh.set_boundary_names(names);
  if (options.rational) {
    Eigen::VectorXd w(count);
    for (int p = 0; p < np; ++p)
      for (int i = 0; i < out.patches[p].mesh.num_functions(); ++i) w[out.global_function[p][i]] = out.patches[p].mesh.weights()[i];
    mesh.set_weights(std::move(w));
  }
  out.first_cell.push_back(0);
  std::vector<int> ids;
  for (int p = 0; p < np; ++p) {
    const BezierMesh& local = out.patches[p].mesh;
    std::vector<int> extraction(local.num_distinct_extractions());
    for (int e = 0; e < local.num_distinct_extractions(); ++e) extraction[e] = mesh.add_extraction(local.pooled_extraction(e));
    std::array<int, 4> boundary_id{-1, -1, -1, -1};  // per CellSide
    for (size_t k = 0; k < exterior.size(); ++k)
      if (exterior[k].patch == p) boundary_id[cell_side_of_patch_side(exterior[k].side)] = static_cast<int>(k);
    for (int c = 0; c < local.num_cells(); ++c) {
      BezierCell cell = local.cell(c);
      cell.patch = p;
      for (int s = 0; s < 4; ++s)
        if (cell.boundary[s] >= 0) cell.boundary[s] = boundary_id[s];
      ids.clear();
      for (int f : local.functions(c)) ids.push_back(out.global_function[p][f]);
      mesh.add_cell(cell, ids, extraction[local.extraction_id(c)]);
    }
    out.first_cell.push_back(mesh.num_cells());
  }

  // The estimator's neighbours: inside every patch, then across its interfaces.
  std::vector<CellInterface> interfaces;
  for (int p = 0; p < np; ++p)
    for (CellInterface ci : interfaces_from_parameter_boxes(out.patches[p].mesh)) {
      ci.cell_a += out.first_cell[p], ci.cell_b += out.first_cell[p];
      interfaces.push_back(ci);
    }
  for (auto [ci, patches] : across) {
    ci.cell_a += out.first_cell[patches[0]];
    ci.cell_b += out.first_cell[patches[1]];
    interfaces.push_back(ci);
  }
  mesh.set_interfaces(std::move(interfaces));
  return out;
}

}  // namespace knotwork
