#include "rkhs/core/cancellation.hpp"

#include <fmt/format.h>

namespace rkhs {
namespace {
thread_local const CancellationScope* current_scope = nullptr;
}  // namespace

TrialCancelled::TrialCancelled() : std::runtime_error("not run: the run was interrupted") {}

TrialTimeLimitExceeded::TrialTimeLimitExceeded(double elapsed)
    : std::runtime_error(fmt::format("time limit exceeded after {:.1f} s", elapsed)),
      elapsed_seconds(elapsed) {}

CancellationScope::CancellationScope(
    const std::function<bool()>& stop_requested,
    std::optional<std::chrono::steady_clock::time_point> deadline) noexcept
    : previous_(current_scope),
      stop_requested_(stop_requested ? &stop_requested : nullptr),
      deadline_(deadline),
      start_(std::chrono::steady_clock::now()) {
  current_scope = this;
}

CancellationScope::~CancellationScope() {
  current_scope = previous_;
}

const CancellationScope* current_cancellation_scope() noexcept {
  return current_scope;
}

SharedCancellationScope::SharedCancellationScope(const CancellationScope* scope) noexcept
    : previous_(current_scope) {
  current_scope = scope;
}

SharedCancellationScope::~SharedCancellationScope() {
  current_scope = previous_;
}

void check_cancelled() {
  const CancellationScope* scope = current_scope;
  if (!scope) return;
  if (scope->stop_requested_ && (*scope->stop_requested_)()) throw TrialCancelled();
  if (scope->deadline_) {
    const auto now = std::chrono::steady_clock::now();
    if (now > *scope->deadline_)
      throw TrialTimeLimitExceeded(std::chrono::duration<double>(now - scope->start_).count());
  }
}

}  // namespace rkhs
