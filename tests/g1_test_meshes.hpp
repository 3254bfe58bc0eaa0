#pragma once
// Quad meshes shared by the G1 tests: the paper's Section 8 mesh, grids, a cube, split prisms, tori,
// fans.
#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <vector>

#include "basis/g1/quad_mesh.hpp"

namespace knotwork::test {

// The paper's Section 8 mesh: three quads around an interior vertex gamma (valence 3), each
// sharing an edge gamma-delta_i with the next; delta_i are boundary vertices of two faces.
inline QuadMesh three_quads() {
  std::vector<Eigen::Vector3d> v{{0, 0, 0}};
  for (int i = 0; i < 3; ++i) {
    const double a = M_PI / 2 + 2 * M_PI * i / 3;
    v.emplace_back(std::cos(a), std::sin(a), 0);  // delta_i: vertices 1, 2, 3
  }
  for (int i = 0; i < 3; ++i) v.push_back(v[1 + i] + v[1 + (i + 1) % 3]);  // outer corners: 4, 5, 6
  std::vector<std::array<int, 4>> f;
  for (int i = 0; i < 3; ++i) f.push_back({0, 1 + i, 4 + i, 1 + (i + 1) % 3});
  return QuadMesh::from_faces(v, f, "three quads");
}

inline QuadMesh grid(int n) {
  std::vector<Eigen::Vector3d> v;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) v.emplace_back(i, j, 0);
  std::vector<std::array<int, 4>> f;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      f.push_back({a, a + 1, a + n + 2, a + n + 1});
    }
  return QuadMesh::from_faces(v, f, "grid");
}

inline QuadMesh cube() {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  // Outward normals, counter-clockwise seen from outside.
  std::vector<std::array<int, 4>> f{{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  return QuadMesh::from_faces(v, f, "cube");
}

// The n-gonal prism with every face split into quads (its centre, corners and edge
// midpoints), as cases/meshes/pentagonal_prism.py writes it for n = 5: corners of valence 3,
// edge midpoints and rectangle centres of valence 4, the two polygon centres of valence n.
inline QuadMesh split_prism(int n) {
  std::vector<Eigen::Vector3d> v;
  for (int z : {1, -1})
    for (int i = 0; i < n; ++i) v.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), z * 0.6);
  std::vector<std::vector<int>> faces{{}, {}};
  for (int i = 0; i < n; ++i) faces[0].push_back(i), faces[1].push_back(2 * n - 1 - i);
  for (int i = 0; i < n; ++i) faces.push_back({i, n + i, n + (i + 1) % n, (i + 1) % n});
  std::map<std::pair<int, int>, int> midpoints;
  auto midpoint = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    if (const auto it = midpoints.find(key); it != midpoints.end()) return it->second;
    v.push_back((v[a] + v[b]) / 2);
    return midpoints[key] = static_cast<int>(v.size()) - 1;
  };
  std::vector<std::array<int, 4>> quads;
  for (const auto& face : faces) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int c : face) centre += v[c] / static_cast<double>(face.size());
    v.push_back(centre);
    const int middle = static_cast<int>(v.size()) - 1, m = static_cast<int>(face.size());
    for (int i = 0; i < m; ++i) {
      const int previous = face[(i + m - 1) % m], corner = face[i], next = face[(i + 1) % m];
      quads.push_back({corner, midpoint(corner, next), middle, midpoint(previous, corner)});
    }
  }
  return QuadMesh::from_faces(v, quads, "split prism");
}

// The crossings (interior vertices with 4 edges) whose neighbours across from each other differ
// in valence, counted from the mesh alone: where the linear symmetric data fail Condition 3.2
// (with b = -1, c = 1 and a linear, eqs. (6)-(7) ask those neighbours for equal 2cos(2pi/n)).
inline std::vector<int> crossings_with_unequal_neighbours(const QuadMesh& m) {
  std::vector<int> out;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const auto& ring = m.ring(v);
    if (ring.boundary || ring.edges.size() != 4) continue;
    std::array<int, 4> across{};
    for (int i = 0; i < 4; ++i) {
      const auto& E = m.edge(ring.edges[i]);
      across[i] = m.valence(E.v[0] == v ? E.v[1] : E.v[0]);
    }
    if (across[0] != across[2] || across[1] != across[3]) out.push_back(v);
  }
  return out;
}

// A torus of n x m quads: every vertex of valence 4, closed, Euler characteristic 0.
inline QuadMesh torus(int n, int m) {
  std::vector<Eigen::Vector3d> v;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n, b = 2 * M_PI * j / m;
      v.emplace_back((3 + std::cos(b)) * std::cos(a), (3 + std::cos(b)) * std::sin(a), std::sin(b));
    }
  std::vector<std::array<int, 4>> f;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int i1 = (i + 1) % n, j1 = (j + 1) % m;
      f.push_back({j * n + i, j * n + i1, j1 * n + i1, j1 * n + i});
    }
  return QuadMesh::from_faces(v, f, "torus");
}

// Univariate splines of degree k on 2n equal intervals, C^1 at the n-1 original knots and
// C^r at the n midpoints: the G1 space on an n x n grid is their tensor product.
inline long univariate_dimension(int n, int k, int r) { return 2L * n * (k + 1) - 2L * (n - 1) - long(n) * (r + 1); }


// F quads around an interior vertex 0 (valence F): vertices 1..F on the unit circle
// (delta_i, rotated by `twist` * i to make the angles uneven), outer corners F+1..2F.
inline QuadMesh fan(int F, double twist = 0) {
  std::vector<Eigen::Vector3d> v{{0, 0, 0}};
  for (int i = 0; i < F; ++i) {
    const double a = 2 * M_PI * i / F + twist * i;
    v.emplace_back(std::cos(a), std::sin(a), 0);
  }
  for (int i = 0; i < F; ++i) v.push_back(0.9 * (v[1 + i] + v[1 + (i + 1) % F]));
  std::vector<std::array<int, 4>> f;
  for (int i = 0; i < F; ++i) f.push_back({0, 1 + i, 1 + F + i, 1 + (i + 1) % F});
  return QuadMesh::from_faces(v, f, "fan");
}

}  // namespace knotwork::test
