// SPDX-License-Identifier: MIT
// The progress line: drawn with a carriage return and erase-to-end-of-line, redrawn by one ticker thread.
#include "progress.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace imps::app {

bool Progress::stderrIsTerminal() { return ::isatty(STDERR_FILENO) == 1 && !std::getenv("IMPS_NO_PROGRESS"); }

Progress::Progress(std::string command) : Progress(std::move(command), stderrIsTerminal()) {}

Progress::Progress(std::string command, bool enabled) : command_(std::move(command)), enabled_(enabled) {
  if (enabled_) ticker_ = std::thread([this] { tick(); });
}

Progress::~Progress() {
  done();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void Progress::phase(std::string label) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  label_ = std::move(label);
  since_ = std::chrono::steady_clock::now();
  draw();
}

void Progress::draw() {
  if (stop_ || label_.empty()) return;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - since_).count();
  std::fflush(stdout);  // what the command printed so far stays above the line
  std::fprintf(stderr, "\r\033[Kpuppeteer %s: %s … %.1f s", command_.c_str(), label_.c_str(), seconds);
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::tick() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(200));
    draw();
  }
}

void Progress::done() {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  label_.clear();
  if (drawn_) {
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
  }
  drawn_ = false;
}

}  // namespace imps::app
