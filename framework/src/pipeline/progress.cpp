#include "rkhs/pipeline/progress.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace rkhs::pipeline {

namespace {
// Durations as a person reads them: 4.2 s, 3 min 05 s, 1 h 02 min.
std::string duration_text(double seconds) {
  if (seconds < 60) return fmt::format("{:.1f} s", seconds);
  const auto whole = static_cast<long long>(seconds);
  if (whole < 3600) return fmt::format("{} min {:02d} s", whole / 60, static_cast<int>(whole % 60));
  return fmt::format("{} h {:02d} min", whole / 3600, static_cast<int>(whole / 60 % 60));
}
}  // namespace

Progress::Progress(std::ostream& out, bool terminal) : out_(out), terminal_(terminal) {}

Progress::~Progress() {
  stop();
}

void Progress::start(std::size_t total) {
  std::lock_guard lock(mutex_);
  total_ = total;
  start_ = last_line_ = Clock::now();
  if (started_ || stopping_ || total == 0) return;
  started_ = true;
  display_ = std::thread([this] { display_loop(); });
}

void Progress::trial_started(std::size_t index) {
  std::lock_guard lock(mutex_);
  in_flight_[index] = Clock::now();
}

void Progress::trial_finished(std::size_t index, bool ok) {
  {
    std::lock_guard lock(mutex_);
    in_flight_.erase(index);
    ++done_;
    if (!ok) ++failed_;
    finished_event_ = true;
  }
  wake_.notify_one();
}

void Progress::message(const std::string& text) {
  std::lock_guard lock(mutex_);
  if (terminal_ && drawn_width_)
    out_ << "\r" << text
         << std::string(drawn_width_ > text.size() ? drawn_width_ - text.size() : 0, ' ') << "\n";
  else
    out_ << text << "\n";
  out_ << std::flush;
  drawn_width_ = 0;
}

void Progress::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_one();
  if (display_.joinable()) display_.join();
}

std::string Progress::line_locked(Clock::time_point now) const {
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const std::size_t total = std::max<std::size_t>(total_, 1);
  // The estimate assumes the trials left cost what the finished ones did on average.
  const std::string eta =
      done_ ? ", ETA " + duration_text(elapsed / static_cast<double>(done_) *
                                       static_cast<double>(total - std::min(done_, total)))
            : std::string();
  std::string running;
  if (!in_flight_.empty()) {
    std::vector<double> ages;
    for (const auto& [index, started] : in_flight_)
      ages.push_back(std::chrono::duration<double>(now - started).count());
    std::sort(ages.rbegin(), ages.rend());
    std::vector<std::string> shown;
    for (std::size_t k = 0; k < std::min<std::size_t>(ages.size(), 3); ++k)
      shown.push_back(duration_text(ages[k]));
    running = fmt::format("; running {}: {}{}", ages.size(), fmt::join(shown, ", "),
                          ages.size() > 3 ? ", ..." : "");
  }
  const std::string counts = fmt::format("{}/{} trials, {} failed, {}{}{}", done_, total_, failed_,
                                         duration_text(elapsed), eta, running);
  if (!terminal_) return counts;
  const std::size_t width = 30, filled = width * std::min(done_, total) / total;
  return fmt::format("[{}{}] {}", std::string(filled, '#'), std::string(width - filled, '-'),
                     counts);
}

void Progress::display_loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait_for(lock, std::chrono::milliseconds(terminal_ ? 500 : 1000));
    const auto now = Clock::now();
    const bool all_done = done_ >= total_;
    if (terminal_) {
      // Redrawn in place; padded so that a shorter line covers the longer one before it.
      const auto text = line_locked(now);
      out_ << "\r" << text
           << std::string(drawn_width_ > text.size() ? drawn_width_ - text.size() : 0, ' ')
           << std::flush;
      drawn_width_ = text.size();
    } else if ((finished_event_ && now - last_line_ >= std::chrono::seconds(2)) ||
               now - last_line_ >= std::chrono::seconds(10) || (all_done && finished_event_)) {
      out_ << "  " << line_locked(now) << "\n" << std::flush;
      last_line_ = now;
      finished_event_ = false;
    }
    if (stopping_ || all_done) break;
  }
  if (terminal_ && drawn_width_) out_ << "\n" << std::flush;
}

}  // namespace rkhs::pipeline
