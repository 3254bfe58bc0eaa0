#include "cases/geometry_file.hpp"

#include <filesystem>

#include "basis/core/input_error.hpp"

namespace knotwork {

MultiPatch read_geometry_file(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  MultiPatch d;
  if (ext == ".xml")
    d = read_gismo_xml(path);
  else if (ext == ".txt")
    d = read_geopdes_text(path);
  else
    throw InputError(path + ": unknown geometry format '" + ext +
                     "' (.xml is read as G+Smo XML, .txt as GeoPDEs' geometry text v2.1)");
  try {
    check_multipatch(d);
  } catch (const GeometryError& e) {
    const std::string m = e.what();
    throw InputError(m.rfind(path, 0) == 0 ? m : path + ": " + m);
  }
  return d;
}

}  // namespace knotwork
