// A sampled road's kinks reach the adaptive integrator: with restart_at_samples the integrator
// restarts at every sample (more segments, far fewer rejected steps), with the same result.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "study_support.hpp"

using namespace rkhs;

TEST_CASE("an adaptive trial restarts at the samples of a piecewise-linear road",
          "[adaptive][csv_road]") {
  const auto file = std::filesystem::temp_directory_path() / "rkhs_road_kinks.csv";
  {
    std::ofstream out(file);
    out << "u,z\n";
    for (int i = 0; i <= 40; ++i)  // 41 samples over 2 m: a rough, closed profile
      out << 0.05 * i << "," << (i % 40 == 0 ? 0.0 : 0.01 * std::sin(1.7 * i * i)) << "\n";
  }
  const std::string study_text = R"(
[study]
name = "road_kinks"
kind = "adaptive"
evaluation_points = 512
metrics = ["l2_error", "final_state_error", "steps", "rejected_steps", "segments"]
[domain]
length = 2.0
[grid]
n = [8]
[[kernel]]
name = "gaussian"
sigma = 0.3
[[target]]
name = "csv"
file = ")" + file.string() + R"("
restart_at_samples = [true, false]
[[law]]
name = "rkhs"
gamma = 2e4
[[integrator]]
name = "rodas4"
rtol = 1e-8
atol = 1e-10
[adaptive]
speed = 1e-4
laps = 2
samples_per_lap = 4
)";
  const auto outcome = test::run_study_text(study_text, "road_kinks.toml");
  REQUIRE(outcome.trials.size() == 2);
  auto metric = [&](std::size_t i, std::string_view name) { return outcome.metric(i, name); };
  // 40 samples per lap (the seam among them), 2 laps: at least 80 segments with restarts; the
  // Gaussian is periodised and smooth, so without them only the output samples cut the run.
  CHECK(metric(0, "segments") >= 80);
  CHECK(metric(1, "segments") < 12);
  CHECK(metric(0, "rejected_steps") < metric(1, "rejected_steps"));
  CHECK(std::abs(metric(0, "l2_error") - metric(1, "l2_error")) < 1e-5 * metric(1, "l2_error"));
  std::filesystem::remove(file);
}
