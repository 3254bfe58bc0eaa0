#include "cases/geometry_file.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "basis/core/input_error.hpp"

namespace knotwork {

std::string read_geometry_text(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a geometry file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read the geometry file (" + ec.message() + ")");
  if (size > (std::uintmax_t(256) << 20)) throw InputError(path + ": the geometry file is larger than 256 MB");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  if (!(in && s << in.rdbuf())) throw InputError(path + ": cannot read the geometry file");
  return s.str();
}

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
