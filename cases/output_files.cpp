#include "cases/output_files.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "basis/core/input_error.hpp"

namespace knotwork {

namespace fs = std::filesystem;

namespace {

// What an interrupted process must remove: the files being written and the folders made for
// them. The signal handler may only call async-signal-safe functions (unlink, rmdir, write,
// _exit), so paths are copied into fixed slots before anything is written to them, and a
// slot is published by an atomic store once its path is complete.
enum CleanupKind { kFree = 0, kFile = 1, kFolder = 2 };
struct CleanupSlot {
  std::atomic<int> kind{kFree};
  char path[PATH_MAX];
};
constexpr int kCleanupSlots = 256;
CleanupSlot cleanup_slots[kCleanupSlots];

// Returns the slot, or -1 when the path is too long or every slot is taken (then an interrupt
// leaves that file in the hidden staging folder, which the next run in the folder removes).
int remember_for_cleanup(const std::string& path, CleanupKind kind) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kCleanupSlots; ++i) {
    int expected = kFree;
    // Reserve with a value no handler acts on, fill, then publish.
    if (cleanup_slots[i].kind.compare_exchange_strong(expected, -1)) {
      std::memcpy(cleanup_slots[i].path, path.c_str(), path.size() + 1);
      cleanup_slots[i].kind.store(kind);
      return i;
    }
  }
  return -1;
}

void forget_for_cleanup(int slot) {
  if (slot >= 0) cleanup_slots[slot].kind.store(kFree);
}

namespace {
volatile sig_atomic_t announce_interrupt = 1;
}  // namespace

extern "C" void remove_partial_output_and_exit(int signal_number) {
  for (int i = 0; i < kCleanupSlots; ++i)
    if (cleanup_slots[i].kind.load() == kFile) ::unlink(cleanup_slots[i].path);
  // Folders last, the newest first: a staging folder lies inside the output folder made for it.
  for (int i = kCleanupSlots - 1; i >= 0; --i)
    if (cleanup_slots[i].kind.load() == kFolder) ::rmdir(cleanup_slots[i].path);
  const char* message = signal_number == SIGINT ? "knotwork: error: interrupted (SIGINT); no partial output left behind\n"
                        : signal_number == SIGTERM ? "knotwork: error: terminated (SIGTERM); no partial output left behind\n"
                                                   : "knotwork: error: hung up (SIGHUP); no partial output left behind\n";
  if (announce_interrupt) {
    ssize_t ignored = ::write(STDERR_FILENO, message, std::strlen(message));
    (void)ignored;
  }
  ::_exit(128 + signal_number);
}

// Signals held back while finished files are moved into place, so that an interrupt never
// leaves one output directory with some files of the new run and some of an older one.
class HoldInterrupts {
 public:
  HoldInterrupts() {
    sigset_t held;
    sigemptyset(&held);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&held, s);
    pthread_sigmask(SIG_BLOCK, &held, &previous_);
  }
  ~HoldInterrupts() { pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }

 private:
  sigset_t previous_;
};

}  // namespace

void remove_partial_output_on_interrupt(bool announce) {
  announce_interrupt = announce ? 1 : 0;
  struct sigaction action {};
  action.sa_handler = remove_partial_output_and_exit;
  sigemptyset(&action.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&action.sa_mask, s);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
}

OutputStage::OutputStage(const std::string& directory) : directory_(directory) {
  std::error_code ec;
  if (fs::exists(directory_, ec) && !fs::is_directory(directory_, ec))
    throw InputError(directory + ": output directory is not writable (it exists and is not a directory)");
  if (!fs::exists(directory_, ec)) {
    // Every folder this makes (results/ and results/case/ for a first run), outermost first,
    // so that a run that fails or is interrupted leaves none of them behind.
    for (fs::path p = fs::absolute(directory_, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec);
         p = p.parent_path()) {
      created_.insert(created_.begin(), p);
      if (p == p.parent_path()) break;
    }
    fs::create_directories(directory_, ec);
    if (ec) {
      remove_created_folders();
      throw InputError(directory + ": output directory is not writable (" + ec.message() + ")");
    }
    for (const fs::path& p : created_) cleanup_slots_.push_back(remember_for_cleanup(p.string(), kFolder));
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
  cleanup_slots_.push_back(remember_for_cleanup(staging_.string(), kFolder));
  fs::create_directory(staging_, ec);
  if (ec || ::access(staging_.c_str(), W_OK) != 0) {
    fs::remove_all(staging_, ec);
    remove_created_folders();
    for (int slot : cleanup_slots_) forget_for_cleanup(slot);
    throw InputError(directory + ": output directory is not writable (" +
                     (ec ? ec.message() : std::string("permission denied")) + ")");
  }
}

OutputStage::~OutputStage() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!committed_) remove_created_folders();
  for (int slot : cleanup_slots_) forget_for_cleanup(slot);
}

void OutputStage::remove_created_folders() {
  std::error_code ec;
  for (auto p = created_.rbegin(); p != created_.rend(); ++p)
    if (fs::is_directory(*p, ec) && fs::is_empty(*p, ec)) fs::remove(*p, ec);
}

std::string OutputStage::stage(const std::string& name) {
  names_.push_back(name);
  const std::string path = (staging_ / name).string();
  cleanup_slots_.push_back(remember_for_cleanup(path, kFile));
  return path;
}

std::vector<std::string> OutputStage::commit() {
  HoldInterrupts hold;
  std::vector<std::string> finals;
  for (const auto& name : names_) {
    const fs::path target = directory_ / name;
    std::error_code ec;
    fs::rename(staging_ / name, target, ec);
    if (ec) throw std::runtime_error(target.string() + ": could not move output into place (" + ec.message() + ")");
    finals.push_back(target.string());
  }
  committed_ = true;
  // Moved into place: from now on an interrupt leaves these files (complete) where they are.
  for (int slot : cleanup_slots_) forget_for_cleanup(slot);
  cleanup_slots_.clear();
  return finals;
}

void write_file_atomically(const std::string& file, const std::string& what,
                           const std::function<void(const std::string& path)>& write) {
  const fs::path target(file);
  const std::string tmp = (target.parent_path() / (".partial." + target.filename().string())).string();
  struct Forget {
    int slot;
    ~Forget() { forget_for_cleanup(slot); }
  } forget{remember_for_cleanup(tmp, kFile)};
  try {
    write(tmp);
  } catch (const std::exception& e) {
    fs::remove(tmp);
    throw InputError(file + ": " + what + ": cannot write the file (" + e.what() + ")");
  }
  std::error_code ec;
  HoldInterrupts hold;
  fs::rename(tmp, file, ec);
  forget_for_cleanup(forget.slot);
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
