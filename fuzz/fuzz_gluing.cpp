// Gluing-data files (JSON) on the three-quad mesh of the shipped G1 case: load_gluing_file
// reads the data edge by edge and checks them (every interior edge once, polynomial pieces,
// compatibility at the vertices).
#include "families/g1/gluing_file.hpp"
#include "fuzz/fuzz_input.hpp"
#include "basis/core/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const knotwork::QuadMesh mesh =
      knotwork::QuadMesh::read_obj(std::string(KNOTWORK_SOURCE_DIR) + "/cases/meshes/three_quads.obj");
  const std::string path = knotwork_fuzz::scratch_file(data, size, "gluing.json");
  try {
    knotwork::load_gluing_file(path, mesh);
  } catch (const knotwork::InputError&) {
  }
  return 0;
}
