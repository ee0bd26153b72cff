#pragma once
// The paper's closed track (radius 4 m), the finest knots of a B-spline kernel on it and the sine
// road of amplitude 2: the setting of the feature-coordinate and excitation tests.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "plugins/kernels/kernel_test_support.hpp"
#include "rkhs/core/domain.hpp"

namespace rkhs::test {

inline const Domain paper_track{track_length, true};

/// The finest knots of a periodic B-spline kernel, s = k L / (n0 2^J), shifted by `offset` cells.
inline std::vector<double> finest_points(std::int64_t n0, std::int64_t levels,
                                         double offset = 0.0) {
  const std::int64_t cells = n0 << levels;
  std::vector<double> out(static_cast<std::size_t>(cells));
  for (std::int64_t k = 0; k < cells; ++k)
    out[static_cast<std::size_t>(k)] =
        paper_track.length * (static_cast<double>(k) + offset) / static_cast<double>(cells);
  return out;
}

/// f(s) = 2 sin(2 pi s / L) and its slope.
inline double sine_road(double s) {
  return 2.0 * std::sin(2 * std::numbers::pi * s / paper_track.length);
}
inline double sine_road_slope(double s) {
  const double w = 2 * std::numbers::pi / paper_track.length;
  return 2.0 * w * std::cos(w * s);
}

}  // namespace rkhs::test
