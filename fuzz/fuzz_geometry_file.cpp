// Geometry files of the peers (KNOTWORK_FUZZ_EXTENSION): GeoPDEs text (.txt) or G+Smo XML
// (.xml), read and checked by read_geometry_file (every patch, interface and boundary list);
// for a domain that reads, its sides' names and the G1 family's quad mesh of bilinear patches.
#include "basis/core/input_error.hpp"
#include "basis/g1/patches_as_quad_mesh.hpp"
#include "cases/geometry_file.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = knotwork_fuzz::scratch_file(data, size, std::string("geometry.") + KNOTWORK_FUZZ_EXTENSION);
  knotwork::MultiPatch domain;
  try {
    domain = knotwork::read_geometry_file(path);
  } catch (const knotwork::InputError&) {
    return 0;
  }
  for (const knotwork::PatchSideRef& s : knotwork::exterior_sides(domain)) (void)knotwork::side_name(domain, s);
  try {
    (void)knotwork::quad_mesh_of_bilinear_patches(domain, path);
  } catch (const knotwork::InputError&) {
  } catch (const std::invalid_argument&) {  // QuadMesh::from_faces's documented refusal
  }
  return 0;
}
