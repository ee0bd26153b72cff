#include "rkhs/core/domain.hpp"

namespace rkhs {

std::vector<double> Domain::uniform_points(std::size_t count) const {
  std::vector<double> points(count);
  if (count == 1) {
    points[0] = periodic ? 0.0 : 0.5 * length;
    return points;
  }
  const double step = periodic ? length / static_cast<double>(count)
                               : length / static_cast<double>(count - 1);
  for (std::size_t m = 0; m < count; ++m) points[m] = static_cast<double>(m) * step;
  if (!periodic && count > 1) points.back() = length;
  return points;
}

double Domain::l2_norm(std::span<const double> values) const {
  const std::size_t count = values.size();
  if (count == 0) return 0.0;
  double sum = 0.0;
  if (periodic || count == 1) {
    for (double v : values) sum += v * v;
    return std::sqrt(sum * length / static_cast<double>(count));
  }
  for (std::size_t m = 0; m < count; ++m) {
    const double weight = (m == 0 || m + 1 == count) ? 0.5 : 1.0;
    sum += weight * values[m] * values[m];
  }
  return std::sqrt(sum * length / static_cast<double>(count - 1));
}

}  // namespace rkhs
