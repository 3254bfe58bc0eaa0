#include "cases/output_files.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>

#include "solver/input_error.hpp"

namespace knotwork {

namespace fs = std::filesystem;

OutputStage::OutputStage(const std::string& directory) : directory_(directory) {
  std::error_code ec;
  if (fs::exists(directory_, ec) && !fs::is_directory(directory_, ec))
    throw InputError(directory + ": output directory is not writable (it exists and is not a directory)");
  if (!fs::exists(directory_, ec)) {
    fs::create_directories(directory_, ec);
    if (ec) throw InputError(directory + ": output directory is not writable (" + ec.message() + ")");
    created_directory_ = true;
  }
  // A run that was killed (Ctrl-C, out of memory) could not clean up after itself: remove
  // staging folders whose process is gone.
  for (const auto& entry : fs::directory_iterator(directory_, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string prefix = ".knotwork-staging-";
    if (name.rfind(prefix, 0) != 0) continue;
    const pid_t owner = static_cast<pid_t>(std::atol(name.c_str() + prefix.size()));
    if (owner > 0 && ::kill(owner, 0) != 0 && errno == ESRCH) fs::remove_all(entry.path(), ec);
  }
  staging_ = directory_ / (".knotwork-staging-" + std::to_string(::getpid()));
  fs::create_directory(staging_, ec);
  if (ec || ::access(staging_.c_str(), W_OK) != 0) {
    fs::remove_all(staging_, ec);
    if (created_directory_) fs::remove(directory_, ec);
    throw InputError(directory + ": output directory is not writable (" +
                     (ec ? ec.message() : std::string("permission denied")) + ")");
  }
}

OutputStage::~OutputStage() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!committed_ && created_directory_ && fs::is_empty(directory_, ec)) fs::remove(directory_, ec);
}

std::string OutputStage::stage(const std::string& name) {
  names_.push_back(name);
  return (staging_ / name).string();
}

std::vector<std::string> OutputStage::commit() {
  std::vector<std::string> finals;
  for (const auto& name : names_) {
    const fs::path target = directory_ / name;
    std::error_code ec;
    fs::rename(staging_ / name, target, ec);
    if (ec) throw std::runtime_error(target.string() + ": could not move output into place (" + ec.message() + ")");
    finals.push_back(target.string());
  }
  committed_ = true;
  return finals;
}

void write_file_atomically(const std::string& file, const std::string& what,
                           const std::function<void(const std::string& path)>& write) {
  const fs::path target(file);
  const std::string tmp = (target.parent_path() / (".partial." + target.filename().string())).string();
  try {
    write(tmp);
  } catch (const std::exception& e) {
    fs::remove(tmp);
    throw InputError(file + ": " + what + ": cannot write the file (" + e.what() + ")");
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec) {
    fs::remove(tmp);
    throw InputError(file + ": " + what + ": cannot write the file (" + ec.message() + ")");
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path + ": could not write");
}

}  // namespace knotwork
