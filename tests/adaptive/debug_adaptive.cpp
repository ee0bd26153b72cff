#include <catch2/catch.hpp>
#include <fstream>
#include <iostream>
#include <sstream>
#include "rkhs/run.hpp"
#include "rkhs/study.hpp"
TEST_CASE("debug adaptive run", "[.debug]") {
  const char* path = std::getenv("RKHS_DEBUG_STUDY");
  REQUIRE(path);
  const auto study = rkhs::load_study(path);
  const auto trials = study.trials();
  const auto results = rkhs::run_trials(study, trials, {2, {}});
  for (const auto& t : trials) {
    const auto& r = results[t.index];
    std::cout << t.key.substr(0, 60) << " ... n=" << t.n << " " << (r.ok ? "ok" : r.reason);
    for (const char* m : {"l2_error", "final_state_error", "steps", "rejected_steps", "segments", "rhs_evaluations"})
      std::cout << " " << m << "=" << r.metrics[study.metric_index(m)];
    std::cout << " " << r.seconds << " s\n";
  }
}
