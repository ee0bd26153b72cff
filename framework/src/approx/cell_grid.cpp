// Points bucketed in a uniform grid of cells (rkhs/approx/cell_grid.hpp).

#include "rkhs/approx/cell_grid.hpp"

#include <algorithm>
#include <cmath>

namespace rkhs {

std::size_t CellGrid::cells() const {
  std::size_t total = 1;
  for (int a = 0; a < dimension; ++a) total *= static_cast<std::size_t>(count[a]);
  return total;
}

std::int64_t CellGrid::axis_cell(const Domain& domain, double x, int axis) const {
  if (periodic) x = domain.wrap(x, axis);
  const auto cell = static_cast<std::int64_t>(std::floor(x / side[axis]));
  return std::clamp<std::int64_t>(cell, 0, count[axis] - 1);
}

std::size_t CellGrid::cell_of(const Domain& domain, const double* x) const {
  std::size_t c = 0;
  for (int a = dimension - 1; a >= 0; --a)
    c = c * static_cast<std::size_t>(count[a]) +
        static_cast<std::size_t>(axis_cell(domain, x[a], a));
  return c;
}

CellGrid::Position CellGrid::position(std::size_t c) const {
  Position at{};
  for (int a = 0; a < dimension; ++a) {
    at[a] = static_cast<std::int64_t>(c % static_cast<std::size_t>(count[a]));
    c /= static_cast<std::size_t>(count[a]);
  }
  return at;
}

CellGrid cells_at_least(const Domain& domain, double radius, std::size_t points) {
  CellGrid grid;
  grid.dimension = domain.dimension;
  grid.periodic = domain.periodic;
  const double budget = 4.0 * static_cast<double>(points) + 64.0;
  for (int a = 0; a < grid.dimension; ++a) {
    const double per_axis = std::floor(domain.extent(a) / radius);
    grid.count[a] = static_cast<std::int64_t>(
        std::clamp(per_axis, 1.0, std::pow(budget, 1.0 / grid.dimension)));
    grid.side[a] = domain.extent(a) / static_cast<double>(grid.count[a]);
  }
  return grid;
}

CellGrid cells_of_one_point(const Domain& domain, std::size_t points) {
  CellGrid grid;
  grid.dimension = domain.dimension;
  grid.periodic = domain.periodic;
  const double spacing =
      std::pow(domain.volume() / static_cast<double>(std::max<std::size_t>(points, 1)),
               1.0 / domain.dimension);
  for (int a = 0; a < grid.dimension; ++a) {
    grid.count[a] = std::max<std::int64_t>(
        1, static_cast<std::int64_t>(std::llround(domain.extent(a) / spacing)));
    grid.side[a] = domain.extent(a) / static_cast<double>(grid.count[a]);
  }
  return grid;
}

void bucket(CellGrid& grid, const Domain& domain, std::span<const double> points) {
  const auto d = static_cast<std::size_t>(grid.dimension);
  const std::size_t n = points.size() / d, cells = grid.cells();
  std::vector<std::size_t> cell_of(n);
  for (std::size_t i = 0; i < n; ++i) cell_of[i] = grid.cell_of(domain, &points[i * d]);
  grid.start.assign(cells + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++grid.start[cell_of[i] + 1];
  for (std::size_t c = 0; c < cells; ++c) grid.start[c + 1] += grid.start[c];
  grid.order.resize(n);
  std::vector<std::size_t> next(grid.start.begin(), grid.start.end() - 1);
  for (std::size_t i = 0; i < n; ++i) grid.order[next[cell_of[i]]++] = i;
  grid.coordinates.resize(n * d);
  for (std::size_t k = 0; k < n; ++k)
    std::copy_n(points.begin() + static_cast<std::ptrdiff_t>(grid.order[k] * d), d,
                grid.coordinates.begin() + static_cast<std::ptrdiff_t>(k * d));
}

void cells_around(const CellGrid& grid, const CellGrid::Position& at, std::int64_t reach,
                  std::vector<std::size_t>& out) {
  out.clear();
  const std::int64_t width = 2 * reach + 1;
  std::int64_t offsets = 1;
  for (int a = 0; a < grid.dimension; ++a) offsets *= width;
  for (std::int64_t o = 0; o < offsets; ++o) {
    std::int64_t code = o;
    std::size_t index = 0, stride = 1;
    bool inside = true;
    for (int a = 0; a < grid.dimension; ++a) {
      std::int64_t x = at[a] + code % width - reach;
      code /= width;
      if (x < 0 || x >= grid.count[a]) {
        if (!grid.periodic) {
          inside = false;
          break;
        }
        x = ((x % grid.count[a]) + grid.count[a]) % grid.count[a];
      }
      index += static_cast<std::size_t>(x) * stride;
      stride *= static_cast<std::size_t>(grid.count[a]);
    }
    if (inside) out.push_back(index);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

std::span<const double> cell_points(const CellGrid& grid, std::size_t c) {
  const auto d = static_cast<std::size_t>(grid.dimension);
  return std::span<const double>(grid.coordinates)
      .subspan(grid.start[c] * d, (grid.start[c + 1] - grid.start[c]) * d);
}

std::span<const std::size_t> cell_indices(const CellGrid& grid, std::size_t c) {
  return std::span<const std::size_t>(grid.order)
      .subspan(grid.start[c], grid.start[c + 1] - grid.start[c]);
}

}  // namespace rkhs
