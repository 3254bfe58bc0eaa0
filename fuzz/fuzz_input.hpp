#pragma once
// What every harness shares: the fuzzer's bytes become a file the real loader reads, in a
// scratch folder where the relative paths of the shipped cases (meshes/, tmeshes/,
// collections/) resolve, so that mutated seeds still reach the files they name.
// A loader may refuse its input only with the exception its header documents (InputError,
// or std::invalid_argument for OBJ); anything else escapes the harness, and libFuzzer
// reports it as a crash, like a sanitizer report, a time-out or running out of memory.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace knotwork_fuzz {

inline const std::filesystem::path& scratch_folder() {
  static const std::filesystem::path dir = [] {
    namespace fs = std::filesystem;
    const fs::path d = fs::temp_directory_path() / ("knotwork-fuzz-" + std::to_string(getpid()));
    fs::create_directories(d);
    for (const char* sub : {"meshes", "tmeshes", "collections"}) {
      const fs::path link = d / sub;
      std::error_code ec;
      if (!fs::exists(link)) fs::create_directory_symlink(fs::path(KNOTWORK_SOURCE_DIR) / "cases" / sub, link, ec);
    }
    return d;
  }();
  return dir;
}

// Writes the bytes to `name` in the scratch folder and returns its path.
inline std::string scratch_file(const uint8_t* data, size_t size, const std::string& name) {
  const std::string path = (scratch_folder() / name).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

}  // namespace knotwork_fuzz
