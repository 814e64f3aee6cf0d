#include "app/progress.h"

#include <csignal>
#include <cstdio>

#include <fmt/format.h>

#include "app/commands.h"

namespace raylab::cli {

namespace {
std::atomic<bool> g_interrupted{false};

extern "C" void on_sigint(int) {
  g_interrupted.store(true);
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends the process at once
}
}  // namespace

ProgressLine::ProgressLine(std::string command, bool enabled)
    : command_(std::move(command)), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

void ProgressLine::update(size_t done, size_t total, const std::string& what) {
  if (!enabled_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string eta;
  if (done > 0 && total > done) {
    const double per_item = elapsed / static_cast<double>(done);
    eta = fmt::format(", {:.2g} s/item, ~{} left", per_item, format_duration(per_item * static_cast<double>(total - done)));
  }
  std::fprintf(stderr, "\r\033[K%s [%zu/%zu, %s elapsed%s] %s", command_.c_str(), done, total,
               format_duration(elapsed).c_str(), eta.c_str(), what.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::clear() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
  drawn_ = false;
}

InterruptGuard::InterruptGuard() {
  g_interrupted.store(false);
  previous_ = std::signal(SIGINT, on_sigint);
}

InterruptGuard::~InterruptGuard() { std::signal(SIGINT, previous_ == SIG_ERR ? SIG_DFL : previous_); }

const std::atomic<bool>* InterruptGuard::flag() const { return &g_interrupted; }
bool InterruptGuard::interrupted() const { return g_interrupted.load(); }

}  // namespace raylab::cli
