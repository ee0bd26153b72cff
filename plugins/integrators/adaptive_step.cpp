#include "rkhs/integrators/adaptive_step.hpp"

namespace rkhs::integrators {

std::vector<ParameterSpec> adaptive_step_parameters() {
  return {positive_parameter("rtol", 1e-6, "relative tolerance"),
          positive_parameter("atol", 1e-8, "absolute tolerance"),
          integer_parameter("max_steps", 20'000'000, "step budget of a trial", 1, 1LL << 40),
          real_parameter("initial_step", 0.0, "first step, s (0: 1e-6 of the first segment)", 0.0),
          boolean_parameter("restart_at_kinks", true,
                            "stop and restart where phi(s(t)) or f(s(t)) has kinks")};
}

}  // namespace rkhs::integrators
