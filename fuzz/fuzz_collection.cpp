// Collection files (B-splines by their local knot vectors, JSON): load_collection, then what
// `knotwork basis` does before its rank and dimension counts — the collection itself, its
// semi-regularity cell by cell and its Bezier extraction — on collections small enough to be
// cheap.
#include "families/knot_segments/knot_segments_case.hpp"
#include "fuzz/fuzz_input.hpp"
#include "basis/core/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = knotwork_fuzz::scratch_file(data, size, "collection.json");
  knotwork::CollectionDescription cd;
  try {
    cd = knotwork::load_collection(path);
  } catch (const knotwork::InputError&) {
    return 0;
  }
  if (cd.splines.size() > 64) return 0;
  try {
    const auto collection = knotwork::SemiRegularCollection::from_splines(cd.dx, cd.dy, cd.splines);
    collection.violations();
    collection.bezier_mesh();
  } catch (const std::invalid_argument&) {  // documented by from_splines (basis names the file)
  } catch (const std::runtime_error&) {     // supports that induce no partition (basis names the file)
  }
  return 0;
}
