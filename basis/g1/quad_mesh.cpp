#include "basis/g1/quad_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace knotwork {

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

// 1-based numbering in messages, as in the OBJ file.
std::string vtx(int i) { return "vertex " + std::to_string(i + 1); }
std::string fc(int f) { return "face " + std::to_string(f + 1); }

}  // namespace

int QuadMesh::find_edge(int a, int b) const {
  if (a == b) return -1;
  for (int e : rings_[a].edges)  // the edges at a: a valence's worth, not the whole mesh
    if (edges_[e].v[0] == b || edges_[e].v[1] == b) return e;
  return -1;
}

bool QuadMesh::closed() const {
  for (const auto& e : edges_)
    if (e.boundary()) return false;
  return true;
}

QuadMesh QuadMesh::read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open the mesh file");
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 4>> faces;
  std::vector<int> face_line;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = path + ":" + std::to_string(number);
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag)) continue;
    if (tag == "v") {
      std::vector<double> xyz;
      std::string word;
      while (s >> word) {
        try {
          size_t used = 0;
          const double x = std::stod(word, &used);
          if (used != word.size() || !std::isfinite(x)) throw std::invalid_argument("");
          xyz.push_back(x);
        } catch (const std::exception&) {
          fail(where, "vertex coordinate '" + word + "' is not a finite number");
        }
      }
      if (xyz.size() < 2 || xyz.size() > 4) fail(where, "a vertex needs x y z (got " + std::to_string(xyz.size()) + " numbers)");
      vertices.emplace_back(xyz[0], xyz[1], xyz.size() > 2 ? xyz[2] : 0.0);
    } else if (tag == "f") {
      std::vector<int> ids;
      std::string word;
      while (s >> word) {
        const std::string head = word.substr(0, word.find('/'));
        long i = 0;
        try {
          size_t used = 0;
          i = std::stol(head, &used);
          if (used != head.size()) throw std::invalid_argument("");
        } catch (const std::out_of_range&) {
          fail(where, "face index " + head + " does not name a vertex defined before it (1.." +
                          std::to_string(vertices.size()) + ")");
        } catch (const std::exception&) {
          fail(where, "face index '" + word + "' is not an integer");
        }
        if (i < 0) i += static_cast<long>(vertices.size()) + 1;  // relative to the vertices so far
        if (i < 1 || i > static_cast<long>(vertices.size()))
          fail(where, "face index " + head + " does not name a vertex defined before it (1.." +
                          std::to_string(vertices.size()) + ")");
        ids.push_back(static_cast<int>(i - 1));
      }
      if (ids.size() != 4)
        fail(where, "face with " + std::to_string(ids.size()) + " vertices: only quadrilaterals are supported");
      faces.push_back({ids[0], ids[1], ids[2], ids[3]});
      face_line.push_back(number);
    } else if (tag == "vt" || tag == "vn" || tag == "o" || tag == "g" || tag == "s" || tag == "usemtl" ||
               tag == "mtllib") {
      continue;
    } else {
      fail(where, "'" + tag + "' is not supported (only v and f, and vt/vn/o/g/s/usemtl/mtllib which are ignored)");
    }
  }
  if (faces.empty()) fail(path, "no faces");
  return from_faces(std::move(vertices), std::move(faces), path);
}

QuadMesh QuadMesh::from_faces(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 4>> faces,
                              const std::string& source) {
  QuadMesh M;
  if (faces.empty()) fail(source, "no faces");
  const int nv = static_cast<int>(vertices.size());
  for (size_t f = 0; f < faces.size(); ++f)
    for (int j = 0; j < 4; ++j) {
      if (faces[f][j] < 0 || faces[f][j] >= nv) fail(source, fc(f) + ": vertex index out of range");
      for (int i = 0; i < j; ++i)
        if (faces[f][i] == faces[f][j]) fail(source, fc(f) + " is degenerate: it uses " + vtx(faces[f][j]) + " twice");
    }
  // Duplicate vertices: equal up to 1e-12 of the mesh size.
  Eigen::Vector3d lo = vertices.front(), hi = vertices.front();
  for (const auto& p : vertices) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double size = std::max((hi - lo).norm(), 1e-300), tol = 1e-12 * size;
  {
    std::vector<int> order(nv);
    for (int i = 0; i < nv; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return vertices[a].x() < vertices[b].x(); });
    for (int a = 0; a < nv; ++a)
      for (int b = a + 1; b < nv && vertices[order[b]].x() - vertices[order[a]].x() <= tol; ++b)
        if ((vertices[order[a]] - vertices[order[b]]).norm() <= tol) {
          const int i = std::min(order[a], order[b]), j = std::max(order[a], order[b]);
          fail(source, vtx(i) + " and " + vtx(j) + " are the same point (duplicate vertices; merge them)");
        }
  }
  std::vector<bool> used(nv, false);
  for (const auto& f : faces)
    for (int v : f) used[v] = true;
  for (int v = 0; v < nv; ++v)
    if (!used[v]) fail(source, vtx(v) + " is in no face (unused vertex)");
  M.planar_ = true;
  for (const auto& p : vertices) M.planar_ = M.planar_ && p.z() == 0;
  // Degenerate faces: the quad's vector area (half the cross product of its diagonals).
  for (size_t f = 0; f < faces.size(); ++f) {
    const auto& q = faces[f];
    const Eigen::Vector3d area =
        0.5 * (vertices[q[2]] - vertices[q[0]]).cross(vertices[q[3]] - vertices[q[1]]);
    if (area.norm() <= 1e-12 * size * size) fail(source, fc(f) + " is degenerate (zero area)");
    if (M.planar_ && area.z() < 0)
      fail(source, fc(f) + " is clockwise in the plane; list every face's vertices counter-clockwise");
  }
  // Edges from half-edges.
  std::map<std::pair<int, int>, int> half;  // (from, to) -> face * 4 + corner
  for (size_t f = 0; f < faces.size(); ++f)
    for (int j = 0; j < 4; ++j) {
      const int a = faces[f][j], b = faces[f][(j + 1) % 4];
      const auto [it, fresh] = half.emplace(std::make_pair(a, b), static_cast<int>(f) * 4 + j);
      if (!fresh) {
        const int g = it->second / 4;
        if (g == static_cast<int>(f)) fail(source, fc(f) + " is degenerate: it runs along one edge twice");
        fail(source, "edge " + std::to_string(a + 1) + "-" + std::to_string(b + 1) + " is traversed the same way by " +
                         fc(g) + " and " + fc(f) + ": the orientation is inconsistent, or the edge is non-manifold");
      }
    }
  M.face_edges_.assign(faces.size(), {-1, -1, -1, -1});
  // An edge in three or more faces has two of them traversing it the same way: the
  // half-edge check above has refused it already.
  for (const auto& [key, id] : half) {
    const int f = id / 4, j = id % 4;
    if (M.face_edges_[f][j] >= 0) continue;
    Edge e;
    e.v = {key.first, key.second};
    e.face[0] = f;
    e.corner[0] = j;
    if (const auto twin = half.find({key.second, key.first}); twin != half.end()) {
      e.face[1] = twin->second / 4;
      e.corner[1] = twin->second % 4;
      M.face_edges_[e.face[1]][e.corner[1]] = static_cast<int>(M.edges_.size());
    }
    M.face_edges_[f][j] = static_cast<int>(M.edges_.size());
    M.edges_.push_back(e);
  }
  // Rings: walk counter-clockwise from face to face around each vertex.
  std::vector<std::vector<std::pair<int, int>>> corners_at(nv);  // (face, corner)
  for (size_t f = 0; f < faces.size(); ++f)
    for (int j = 0; j < 4; ++j) corners_at[faces[f][j]].push_back({static_cast<int>(f), j});
  M.rings_.resize(nv);
  for (int v = 0; v < nv; ++v) {
    // Next face ccw: the one whose outgoing edge is this face's previous edge (v -> p_{j-1}).
    auto next = [&](int f, int j) -> std::pair<int, int> {
      const auto it = half.find({v, faces[f][(j + 3) % 4]});
      if (it == half.end()) return {-1, -1};
      return {it->second / 4, it->second % 4};
    };
    // A boundary vertex starts at the face whose outgoing edge has no face before it.
    std::pair<int, int> start = corners_at[v].front();
    bool boundary = false;
    for (const auto& [f, j] : corners_at[v])
      if (half.find({faces[f][(j + 1) % 4], v}) == half.end()) {
        if (boundary) fail(source, vtx(v) + " is non-manifold (its faces form more than one fan)");
        start = {f, j};
        boundary = true;
      }
    Ring& r = M.rings_[v];
    r.boundary = boundary;
    std::pair<int, int> at = start;
    do {
      r.faces.push_back(at.first);
      r.corners.push_back(at.second);
      r.edges.push_back(M.face_edges_[at.first][at.second]);
      const auto n = next(at.first, at.second);
      if (n.first < 0) {  // reached the boundary: the last edge is this face's previous edge
        r.edges.push_back(M.face_edges_[at.first][(at.second + 3) % 4]);
        break;
      }
      at = n;
    } while (at != start && r.faces.size() <= corners_at[v].size());
    if (r.faces.size() != corners_at[v].size())
      fail(source, vtx(v) + " is non-manifold (its " + std::to_string(corners_at[v].size()) +
                       " faces do not form one fan around it)");
  }
  M.vertices_ = std::move(vertices);
  M.faces_ = std::move(faces);
  return M;
}

}  // namespace knotwork
