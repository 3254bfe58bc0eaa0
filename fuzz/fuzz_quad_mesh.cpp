// Quad meshes, Wavefront OBJ: QuadMesh::read_obj checks faces, indices, orientation and
// manifoldness, then the topology the G1 construction walks: every vertex's ring, every
// face's edges, and the parity of the Euler characteristic of a closed mesh.
#include "basis/g1/quad_mesh.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = knotwork_fuzz::scratch_file(data, size, "mesh.obj");
  try {
    const knotwork::QuadMesh mesh = knotwork::QuadMesh::read_obj(path);
    long walked = 0;  // touches every ring and edge: what a bad index would break
    for (int v = 0; v < mesh.num_vertices(); ++v) walked += mesh.valence(v) + mesh.ring(v).faces.size();
    for (int f = 0; f < mesh.num_faces(); ++f)
      for (int j = 0; j < 4; ++j) walked += mesh.edge(mesh.face_edge(f, j)).boundary();
    (void)walked;
    // A closed oriented manifold has an even Euler characteristic (2 - 2g per component).
    if (mesh.closed() && mesh.euler_characteristic() % 2 != 0) __builtin_trap();
  } catch (const std::invalid_argument&) {  // the refusal read_obj documents
  }
  return 0;
}
