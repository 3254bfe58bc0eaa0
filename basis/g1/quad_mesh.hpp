#pragma once
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace knotwork {

// A quad mesh of arbitrary topology (planar, or a surface in R^3, open or closed) with its
// topology: the domain of the G1 macro-patch splines (Blidia-Mourrain-Villamizar).
// Faces list their vertices counter-clockwise (p0, p1, p2, p3) -> (0,0), (1,0), (1,1), (0,1)
// in face coordinates (s, t).
class QuadMesh {
 public:
  // An edge between vertices v[0] and v[1]. face[0] traverses it as v[0] -> v[1] (its
  // local edge corner[0] -> corner[0]+1), face[1] as v[1] -> v[0]; face[1] = -1 on the boundary.
  struct Edge {
    std::array<int, 2> v;
    std::array<int, 2> face{-1, -1};
    std::array<int, 2> corner{-1, -1};  // index (0..3) of the face's corner where its traversal starts
    bool boundary() const { return face[1] < 0; }
  };
  // The faces around a vertex, counter-clockwise: face i occupies the sector from its
  // outgoing edge (towards its next corner) to its previous edge. On the boundary the first
  // face's outgoing edge and the last face's previous edge are boundary edges.
  struct Ring {
    std::vector<int> faces;    // face indices
    std::vector<int> corners;  // the vertex's corner index in each face
    std::vector<int> edges;    // edges[i] = outgoing edge of faces[i]; edges.back() closes the fan
    bool boundary = false;
  };

  // Reads a Wavefront OBJ file (`v x y z`, `f a b c d`, 1-based or negative indices;
  // vt/vn/o/g/s/usemtl/mtllib lines are ignored). Throws std::invalid_argument
  // "<path>:<line>: ..." or "<path>: ..." for anything that is not a valid oriented quad
  // mesh: non-quad faces, bad indices, degenerate faces, duplicate or unused vertices,
  // edges in more than two faces, inconsistent orientation, non-manifold vertices,
  // clockwise planar meshes.
  static QuadMesh read_obj(const std::string& path);
  // The same checks on data in memory (`source` names it in messages); faces 0-based.
  static QuadMesh from_faces(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 4>> faces,
                             const std::string& source = "mesh");

  int num_vertices() const { return static_cast<int>(vertices_.size()); }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  int num_edges() const { return static_cast<int>(edges_.size()); }
  const Eigen::Vector3d& vertex(int i) const { return vertices_[i]; }
  const std::array<int, 4>& face(int f) const { return faces_[f]; }
  const Edge& edge(int e) const { return edges_[e]; }
  // Edge index between two vertices, -1 if none.
  int find_edge(int a, int b) const;
  // The edge of face f from corner j to corner j+1.
  int face_edge(int f, int j) const { return face_edges_[f][j]; }
  const Ring& ring(int v) const { return rings_[v]; }
  bool boundary_vertex(int v) const { return rings_[v].boundary; }
  // Number of edges at the vertex (faces around it, plus one on the boundary).
  int valence(int v) const { return static_cast<int>(rings_[v].edges.size()); }
  bool planar() const { return planar_; }  // every z = 0
  bool closed() const;                      // no boundary edge
  int euler_characteristic() const { return num_vertices() - num_edges() + num_faces(); }

 private:
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<std::array<int, 4>> faces_;
  std::vector<std::array<int, 4>> face_edges_;
  std::vector<Edge> edges_;
  std::vector<Ring> rings_;
  bool planar_ = true;
};

}  // namespace knotwork
