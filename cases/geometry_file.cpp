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

namespace {

// The file's format from its extension: true for G+Smo XML, false for GeoPDEs text.
bool is_gismo_file(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".xml" && ext != ".txt")
    throw InputError(path + ": unknown geometry format '" + ext +
                     "' (.xml is read as G+Smo XML, .txt as GeoPDEs' geometry text v2.1)");
  return ext == ".xml";
}

}  // namespace

int geometry_file_dimension(const std::string& path) {
  return is_gismo_file(path) ? gismo_xml_dimension(path) : geopdes_text_dimension(path);
}

VolumeFile read_volume_file(const std::string& path) {
  VolumeFile v = is_gismo_file(path) ? read_gismo_volume(path) : read_geopdes_volume(path);
  if (v.domain.num_patches() > 1) {
    try {
      check_multivolume(v.domain);
    } catch (const GeometryError& e) {
      const std::string m = e.what();
      throw InputError(m.rfind(path, 0) == 0 ? m : path + ": " + m);
    }
    return v;
  }
  try {
    v.volume.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(v.where + ": " + e.what());
  }
  return v;
}

MultiPatch read_geometry_file(const std::string& path) {
  MultiPatch d = is_gismo_file(path) ? read_gismo_xml(path) : read_geopdes_text(path);
  try {
    check_multipatch(d);
  } catch (const GeometryError& e) {
    const std::string m = e.what();
    throw InputError(m.rfind(path, 0) == 0 ? m : path + ": " + m);
  }
  return d;
}

}  // namespace knotwork
