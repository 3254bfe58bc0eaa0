#pragma once
#include <chrono>
#include <cstdio>
#include <string>

namespace knotwork {

// Progress lines on stderr ("knotwork: level 2/4: assembly"), silent with --quiet.
class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet) {}
  void operator()(const std::string& what) const {
    if (quiet_) return;
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "knotwork [%7.2f s] %s%s\n", t, prefix_.c_str(), what.c_str());
  }
  void set_prefix(std::string p) { prefix_ = std::move(p); }

 private:
  bool quiet_;
  std::string prefix_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace knotwork
