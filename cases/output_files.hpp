#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace knotwork {

// Output files are written into a hidden staging folder inside the output directory and
// moved into place only by commit(): a run that fails leaves no partial output behind.
class OutputStage {
 public:
  // Creates the directory if needed; throws InputError if it cannot be written.
  explicit OutputStage(const std::string& directory);
  ~OutputStage();
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;
  // Path to write `name` to (inside the staging folder); remembers it for commit().
  std::string stage(const std::string& name);
  // Moves every staged file into the directory; returns their final paths.
  std::vector<std::string> commit();

 private:
  std::filesystem::path directory_, staging_;
  std::vector<std::string> names_;
  std::vector<int> cleanup_slots_;  // what an interrupt removes (remove_partial_output_on_interrupt)
  std::vector<std::filesystem::path> created_;  // folders made for the output, outermost first
  bool committed_ = false;
  void remove_created_folders();
};

// A single output file (e.g. --export): `write` fills a hidden sibling, which is renamed to
// `file` only when it succeeded; otherwise it is removed and InputError names the file and
// the option `what`.
void write_file_atomically(const std::string& file, const std::string& what,
                           const std::function<void(const std::string& path)>& write);

// For the command line: SIGINT, SIGTERM and SIGHUP remove every file still being written
// (staged, or a hidden sibling of write_file_atomically) and the folders made for them, print
// one line ("knotwork: error: interrupted (SIGINT); ...") and exit with 128 + the signal.
// Files already moved into place stay: they are complete. Not for the Python module, whose
// interpreter handles Ctrl-C itself. announce = false: no line (the ranks of mpirun but the
// first, which mpirun stops when the first has failed).
void remove_partial_output_on_interrupt(bool announce = true);

// Writes `text` to `path` (a staged file); throws std::runtime_error naming it on failure.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace knotwork
