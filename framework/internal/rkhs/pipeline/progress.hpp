#pragma once
// The progress display of `rkhs-study run` and of the Python module's Study.run(progress=True)
// (python/src/module.cpp, which hands it a stream whose text the calling Python thread writes to
// sys.stderr): trials done and failed, elapsed time, an estimate of the time left, and the
// trials in flight with how long each has run, so that a single long trial shows it is alive.
//
// On a terminal the line is redrawn in place about twice a second; elsewhere (a log, CI) a line
// is written when a trial finishes, at most every few seconds, and every 10 s while trials run.
// Thread-safe: the callbacks may come from any thread; a display thread of its own redraws.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <map>
#include <mutex>
#include <ostream>
#include <string>
#include <thread>

namespace rkhs::pipeline {

class Progress {
 public:
  /// Writes to `out`; `terminal`: redraw one line in place (else write lines).
  Progress(std::ostream& out, bool terminal);
  ~Progress();  ///< stops the display thread (a last line on a terminal ends with a newline)
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void start(std::size_t total);  ///< trials about to run; starts the display
  void trial_started(std::size_t index);
  void trial_finished(std::size_t index, bool ok);
  /// Writes `text` on a line of its own (on a terminal, above the progress line).
  void message(const std::string& text);
  /// Ends the display: no line is written after this returns.
  void stop();

 private:
  using Clock = std::chrono::steady_clock;
  std::string line_locked(Clock::time_point now) const;
  void display_loop();

  std::ostream& out_;
  const bool terminal_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread display_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_line_ = start_;
  std::size_t total_ = 0, done_ = 0, failed_ = 0;
  std::map<std::size_t, Clock::time_point> in_flight_;  ///< trial index -> start time
  bool finished_event_ = false;                         ///< a trial finished since the last line
  std::size_t drawn_width_ = 0;  ///< of the line on the terminal now (0: none drawn)
  bool stopping_ = false, started_ = false;
};

}  // namespace rkhs::pipeline
