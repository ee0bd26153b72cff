#include "rkhs/core/domain.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace rkhs {

namespace {
// The m points of one axis of extent `extent`: m L / M periodic, m L / (M - 1) on an interval,
// the midpoint for M = 1 on an interval.
std::vector<double> axis_points(double extent, bool periodic, std::size_t count) {
  std::vector<double> points(count);
  if (count == 1) {
    points[0] = periodic ? 0.0 : 0.5 * extent;
    return points;
  }
  const double step =
      periodic ? extent / static_cast<double>(count) : extent / static_cast<double>(count - 1);
  for (std::size_t m = 0; m < count; ++m) points[m] = static_cast<double>(m) * step;
  if (!periodic) points.back() = extent;
  return points;
}

// Quadrature weights of axis_points, summing to the extent.
std::vector<double> axis_weights(double extent, bool periodic, std::size_t count) {
  std::vector<double> weights(count);
  if (count == 1) {
    weights[0] = extent;
    return weights;
  }
  if (periodic) {
    std::fill(weights.begin(), weights.end(), extent / static_cast<double>(count));
    return weights;
  }
  const double step = extent / static_cast<double>(count - 1);
  for (std::size_t m = 0; m < count; ++m)
    weights[m] = (m == 0 || m + 1 == count) ? 0.5 * step : step;
  return weights;
}

std::size_t power(std::size_t base, int exponent) {
  std::size_t out = 1;
  for (int i = 0; i < exponent; ++i) out *= base;
  return out;
}
}  // namespace

void Domain::validate() const {
  if (dimension < 1 || dimension > max_dimension)
    throw std::invalid_argument(
        fmt::format("domain dimension {} is not supported (1 to {})", dimension, max_dimension));
  static constexpr const char* names[] = {"length", "width", "height"};
  for (int a = 0; a < dimension; ++a)
    if (!(extent(a) >= min_extent && extent(a) <= max_extent))
      throw std::invalid_argument(fmt::format("domain {} must be between {} and {} metres, not {}",
                                              names[a], min_extent, max_extent, extent(a)));
}

std::size_t Domain::points_per_axis(std::size_t count) const {
  if (dimension == 1) return count;
  auto m =
      static_cast<std::size_t>(std::llround(std::pow(static_cast<double>(count), 1.0 / dimension)));
  return std::max<std::size_t>(m, 2);
}

std::vector<double> Domain::uniform_points(std::size_t count) const {
  if (dimension == 1) return axis_points(length, periodic, count);
  const std::size_t m = points_per_axis(count);
  std::array<std::vector<double>, max_dimension> axes;
  for (int a = 0; a < dimension; ++a) axes[a] = axis_points(extent(a), periodic, m);
  const std::size_t total = power(m, dimension), d = static_cast<std::size_t>(dimension);
  std::vector<double> points(total * d);
  for (std::size_t p = 0; p < total; ++p) {
    std::size_t rest = p;
    for (std::size_t a = 0; a < d; ++a) {
      points[p * d + a] = axes[a][rest % m];
      rest /= m;
    }
  }
  return points;
}

double Domain::l2_norm(std::span<const double> values) const {
  const std::size_t count = values.size();
  if (count == 0) return 0.0;
  if (dimension == 1) {
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
  const std::size_t m = points_per_axis(count);
  if (power(m, dimension) != count)
    throw std::invalid_argument(fmt::format(
        "Domain::l2_norm: {} values are not a tensor grid of {} dimensions", count, dimension));
  std::array<std::vector<double>, max_dimension> weights;
  for (int a = 0; a < dimension; ++a) weights[a] = axis_weights(extent(a), periodic, m);
  double sum = 0.0;
  for (std::size_t p = 0; p < count; ++p) {
    std::size_t rest = p;
    double weight = 1.0;
    for (int a = 0; a < dimension; ++a) {
      weight *= weights[a][rest % m];
      rest /= m;
    }
    sum += weight * values[p] * values[p];
  }
  return std::sqrt(sum);
}

std::string Domain::describe() const {
  const char close = periodic ? ')' : ']';
  std::string out;
  for (int a = 0; a < dimension; ++a) {
    if (a) out += " x ";
    out += fmt::format("[0, {}{}", extent(a), close);
  }
  if (periodic) out += dimension == 1 ? " periodic" : " periodic (torus)";
  return out;
}

}  // namespace rkhs
