#pragma once
// What every built-in adaptive-step integrator reads from its parameters: tolerances, the step
// budget, the first step and whether to restart at kinks (docs/adaptive.md).

#include <cstdint>
#include <vector>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/core/parameters.hpp"

namespace rkhs::integrators {

/// rtol, atol, max_steps, initial_step, restart_at_kinks.
std::vector<ParameterSpec> adaptive_step_parameters();

class AdaptiveStepIntegrator : public Integrator {
 public:
  explicit AdaptiveStepIntegrator(const ParameterSet& p)
      : rtol_(p.real("rtol")),
        atol_(p.real("atol")),
        max_steps_(p.integer("max_steps")),
        initial_step_(p.real("initial_step")),
        restart_(p.boolean("restart_at_kinks")) {}
  bool restarts_at_kinks() const noexcept override { return restart_; }

 protected:
  double rtol_, atol_;
  std::int64_t max_steps_;
  double initial_step_;
  bool restart_;
};

}  // namespace rkhs::integrators
