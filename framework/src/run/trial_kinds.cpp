// The run layer's table of study kinds (rkhs/run/trial_kinds.hpp).
#include "rkhs/run/trial_kinds.hpp"

namespace rkhs {

const TrialKind& trial_kind(StudyKind kind) noexcept {
  switch (kind) {
    case StudyKind::approximation:
      return approximation_trials;
    case StudyKind::adaptive:
      return adaptive_trials;
  }
  return approximation_trials;
}

}  // namespace rkhs
