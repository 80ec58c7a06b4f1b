// SPDX-License-Identifier: MIT
// Progress of long work, shown on a terminal only: one status line on stderr ("puppeteer mesh: polygonizing …
// 1.4 s"), redrawn by a ticker thread and erased when the work is done, so that meshing ten million triangles does
// not run for seconds in silence. When stderr is not a terminal (a pipe, a log file, a test) nothing is printed.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace imps::app {

class Progress {
 public:
  // `command` names the line ("mesh"). enabled: whether to print at all (default: stderr is a terminal, and
  // IMPS_NO_PROGRESS is not set).
  explicit Progress(std::string command);
  Progress(std::string command, bool enabled);
  ~Progress();  // done(), and the ticker stops
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // The work now under way ("polygonizing", "writing out.ply", "render 120/300"); drawn at once, then redrawn
  // with the time spent in it every 200 ms. Thread-safe.
  void phase(std::string label);
  // Erases the line (before the command prints its report or an error); a later phase() shows it again.
  void done();
  bool enabled() const { return enabled_; }

  // Whether progress goes to this process's stderr by default.
  static bool stderrIsTerminal();

 private:
  void draw();  // holds mutex_
  void tick();

  std::string command_;
  bool enabled_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::string label_;
  std::chrono::steady_clock::time_point since_;
  bool stop_ = false, drawn_ = false;
  std::thread ticker_;
};

}  // namespace imps::app
