#include "basis/g1/patches_as_quad_mesh.hpp"


#include "basis/core/disjoint_sets.hpp"
#include "basis/core/input_error.hpp"

namespace knotwork {

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
  DisjointSets copies(first.back());
  for (const PatchInterface& f : domain.interfaces) {
    const NurbsPatch &a = domain.patches[f.a.patch], &b = domain.patches[f.b.patch];
    const std::vector<int> va = side_indices(a.basis_u.num_functions(), a.basis_v.num_functions(), f.a.side);
    std::vector<int> vb = side_indices(b.basis_u.num_functions(), b.basis_v.num_functions(), f.b.side);
    if (va.size() != vb.size())
      throw GeometryError(f.where + ": the sides of patch " + patch_label(domain, f.a.patch) + " and patch " +
                          patch_label(domain, f.b.patch) + " have " + std::to_string(va.size()) + " and " +
                          std::to_string(vb.size()) + " vertices: a quad mesh needs the same vertices on both sides");
    if (f.reversed) std::reverse(vb.begin(), vb.end());
    for (size_t k = 0; k < va.size(); ++k)
      copies.unite(first[f.a.patch] + va[k], first[f.b.patch] + vb[k]);
  }
  int count = 0;
  const std::vector<int> number = copies.numbering(&count);
  std::vector<Eigen::Vector3d> vertices(count);
  std::vector<char> placed(count, 0);
  for (int p = 0; p < domain.num_patches(); ++p)  // a glued vertex where its first copy is
    for (int i = first[p]; i < first[p + 1]; ++i)
      if (!placed[number[i]]) {
        const Eigen::RowVector2d x = domain.patches[p].control_points.row(i - first[p]);
        vertices[number[i]] = Eigen::Vector3d(x[0], x[1], 0.0);
        placed[number[i]] = 1;
      }
  std::vector<std::array<int, 4>> faces;
  for (int p = 0; p < domain.num_patches(); ++p) {
    const int nu = domain.patches[p].basis_u.num_functions(), nv = domain.patches[p].basis_v.num_functions();
    auto v = [&](int i, int j) { return number[first[p] + i + nu * j]; };
    // Counter-clockwise: check_multipatch has found every patch positively oriented.
    for (int j = 0; j + 1 < nv; ++j)
      for (int i = 0; i + 1 < nu; ++i) faces.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)});
  }
  return QuadMesh::from_faces(std::move(vertices), std::move(faces), source);
}

}  // namespace knotwork
