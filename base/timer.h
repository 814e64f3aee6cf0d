#pragma once
#include <chrono>
#include <ctime>

namespace raylab {

class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  void reset() { start_ = std::chrono::steady_clock::now(); }
  double ms() const { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count(); }
  double seconds() const { return ms() * 1e-3; }

 private:
  std::chrono::steady_clock::time_point start_;
};

// CPU time of the calling thread (CLOCK_THREAD_CPUTIME_ID). Single-threaded trace
// timings use it: on a shared 2-core machine, wall time includes the time the
// thread waited for a core, which no property of the accelerator explains.
class ThreadCpuTimer {
 public:
  ThreadCpuTimer() : start_(now()) {}
  double seconds() const { return now() - start_; }

 private:
  static double now() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
  }
  double start_;
};

}  // namespace raylab
