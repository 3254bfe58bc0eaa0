// The plain C0 multipatch space on the same faces and split knots: the baseline the G1
// space is compared against ([space] smoothness = "c0").
#include <map>
#include <stdexcept>

#include "basis/g1/g1_basis.hpp"

namespace knotwork {

G1Basis c0_multipatch_basis(const QuadMesh& mesh, int k, int r) {
  if (k < 1 || r < 0 || r >= k) throw std::invalid_argument("c0_multipatch_basis: need 0 <= r < k");
  G1Basis basis;
  basis.k = k;
  basis.r = r;
  const int n = 2 * k - r + 1;
  basis.space.unknowns = static_cast<long>(mesh.num_faces()) * n * n;
  // Union-find over the coefficients: along an interior edge, the side rows of both faces
  // are the same univariate spline (f1(u, 0) = f0(0, u)), coefficient by coefficient.
  std::vector<long> parent(basis.space.unknowns);
  for (long i = 0; i < basis.space.unknowns; ++i) parent[i] = i;
  auto find = [&](long x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int e = 0; e < mesh.num_edges(); ++e) {
    const auto& E = mesh.edge(e);
    if (E.boundary()) continue;
    for (int a = 0; a < n; ++a) {
      const long x = find(g1_corner_unknown(E.face[0], E.corner[0], a, 0, k, r));
      const long y = find(g1_corner_unknown(E.face[1], (E.corner[1] + 1) % 4, 0, a, k, r));
      if (x != y) parent[std::max(x, y)] = std::min(x, y);
    }
  }
  std::map<long, int> function_of_root;
  for (long i = 0; i < basis.space.unknowns; ++i) {
    const long root = find(i);
    auto [it, added] = function_of_root.emplace(root, static_cast<int>(basis.functions.size()));
    if (added) basis.functions.push_back({G1BasisFunction::Kind::face, static_cast<int>(i / (n * n)), {}});
    basis.functions[it->second].coefficients.emplace_back(i, 1.0);
  }
  basis.space.dimension = static_cast<long>(basis.functions.size());
  basis.counts[static_cast<int>(G1BasisFunction::Kind::face)] = basis.space.dimension;
  basis.exact = true;
  return basis;
}

}  // namespace knotwork
