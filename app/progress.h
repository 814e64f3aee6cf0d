#pragma once
// A one-line progress display on stderr with rate and time estimate, drawn
// only when stderr is a terminal (so logs and pipes stay clean), plus the
// Ctrl-C flag shared by the long-running subcommands: the first Ctrl-C asks
// the command to stop after the current item and keep what it finished
// (exit 130); a second one ends the process at once.
#include <atomic>
#include <chrono>
#include <string>

namespace raylab::cli {

class ProgressLine {
 public:
  ProgressLine(std::string command, bool enabled);
  ~ProgressLine() { clear(); }
  // `done` of `total` items finished; `what` is the current item.
  void update(size_t done, size_t total, const std::string& what);
  void clear();
  bool enabled() const { return enabled_; }

 private:
  std::string command_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_;
};

// Installs the SIGINT handler for the lifetime of the object.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  const std::atomic<bool>* flag() const;
  bool interrupted() const;

 private:
  void (*previous_)(int);
};

}  // namespace raylab::cli
