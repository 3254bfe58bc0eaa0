#include "basis/g1/patches_as_quad_mesh.hpp"

#include <numeric>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace {

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The grid vertices along side 1..4 of an nu x nv grid, in the side's direction.
std::vector<int> side_vertices(int nu, int nv, int side) {
  std::vector<int> out;
  const int n = side <= 2 ? nv : nu;
  for (int k = 0; k < n; ++k)
    out.push_back(side == 1 ? nu * k : side == 2 ? nu - 1 + nu * k : side == 3 ? k : k + nu * (nv - 1));
  return out;
}

}  // namespace

QuadMesh quad_mesh_of_bilinear_patches(const MultiPatch& domain, const std::string& source) {
  std::vector<int> first{0};
  for (int p = 0; p < domain.num_patches(); ++p) {
    const NurbsPatch& patch = domain.patches[p];
    const std::string where = (p < static_cast<int>(domain.patch_where.size()) ? domain.patch_where[p] + ": " : "") +
                              "patch " + patch_label(domain, p);
    if (patch.basis_u.degree() != 1 || patch.basis_v.degree() != 1)
      throw GeometryError(where + " has degree " + std::to_string(patch.basis_u.degree()) + "x" +
                          std::to_string(patch.basis_v.degree()) +
                          ": the G1 family builds on quad meshes, whose patches are bilinear (degree 1x1); curved "
                          "patches are refused (the tensor and THB families take them)");
    for (const BSplineBasis1D* b : {&patch.basis_u, &patch.basis_v}) {
      const auto m = b->multiplicities();
      for (size_t i = 1; i + 1 < m.size(); ++i)
        if (m[i] != 1)
          throw GeometryError(where + " has a repeated interior knot: its control points are not the vertices of one "
                                      "grid of quads (give each piece as a patch of its own)");
    }
    if ((patch.weights.array() != patch.weights[0]).any())
      throw GeometryError(where + " has unequal weights (a rational bilinear patch is curved): the G1 family builds on "
                                  "quad meshes of bilinear patches");
    first.push_back(first.back() + patch.basis_u.num_functions() * patch.basis_v.num_functions());
  }
  std::vector<int> parent(first.back());
  std::iota(parent.begin(), parent.end(), 0);
  for (const PatchInterface& f : domain.interfaces) {
    const NurbsPatch &a = domain.patches[f.a.patch], &b = domain.patches[f.b.patch];
    const std::vector<int> va = side_vertices(a.basis_u.num_functions(), a.basis_v.num_functions(), f.a.side);
    std::vector<int> vb = side_vertices(b.basis_u.num_functions(), b.basis_v.num_functions(), f.b.side);
    if (va.size() != vb.size())
      throw GeometryError(f.where + ": the sides of patch " + patch_label(domain, f.a.patch) + " and patch " +
                          patch_label(domain, f.b.patch) + " have " + std::to_string(va.size()) + " and " +
                          std::to_string(vb.size()) + " vertices: a quad mesh needs the same vertices on both sides");
    if (f.reversed) std::reverse(vb.begin(), vb.end());
    for (size_t k = 0; k < va.size(); ++k)
      parent[find_root(parent, first[f.a.patch] + va[k])] = find_root(parent, first[f.b.patch] + vb[k]);
  }
  std::vector<int> number(parent.size(), -1);
  std::vector<Eigen::Vector3d> vertices;
  for (int p = 0; p < domain.num_patches(); ++p)
    for (int i = first[p]; i < first[p + 1]; ++i) {
      int& n = number[find_root(parent, i)];
      if (n < 0) {
        n = static_cast<int>(vertices.size());
        const Eigen::RowVector2d x = domain.patches[p].control_points.row(i - first[p]);
        vertices.emplace_back(x[0], x[1], 0.0);
      }
    }
  std::vector<std::array<int, 4>> faces;
  for (int p = 0; p < domain.num_patches(); ++p) {
    const int nu = domain.patches[p].basis_u.num_functions(), nv = domain.patches[p].basis_v.num_functions();
    auto v = [&](int i, int j) { return number[find_root(parent, first[p] + i + nu * j)]; };
    // Counter-clockwise: check_multipatch has found every patch positively oriented.
    for (int j = 0; j + 1 < nv; ++j)
      for (int i = 0; i + 1 < nu; ++i) faces.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)});
  }
  return QuadMesh::from_faces(std::move(vertices), std::move(faces), source);
}

}  // namespace knotwork
