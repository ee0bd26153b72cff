// The power function's sup over the evaluation points from local upper bounds and a few exact
// evaluations (rkhs/approx/sparse_gram.hpp, bounded_power_sup).

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "rkhs/approx/cell_grid.hpp"
#include "rkhs/approx/sparse_gram.hpp"
#include "rkhs/core/cancellation.hpp"
#include "rkhs/core/concurrency.hpp"

namespace rkhs {

namespace {
constexpr double eps = std::numeric_limits<double>::epsilon();
// |Y| for the bounds of every point (one set per cell of points), and for the tightened bounds
// of the points that stay candidates when more than refine_above of them do.
constexpr std::size_t cell_subset_size = 64;
constexpr std::size_t point_subset_size = 256;
constexpr std::size_t exact_block = 32;
constexpr std::size_t refine_above = 8 * exact_block;

// The `size` centres nearest `q` (ties to the lower index), in increasing index order: the
// cubes of cells around q's cell grow until the size-th nearest found lies closer than any
// centre outside the cube can.
void nearest_centres(const CellGrid& grid, const Domain& domain, std::span<const double> centres,
                     const double* q, std::size_t size, std::vector<std::size_t>& out) {
  const auto d = static_cast<std::size_t>(grid.dimension);
  const std::size_t n = domain.point_count(centres);
  size = std::min(size, n);
  CellGrid::Position at{};
  double side = std::numeric_limits<double>::infinity();
  for (int a = 0; a < grid.dimension; ++a) {
    at[a] = grid.axis_cell(domain, q[a], a);
    side = std::min(side, grid.side[a]);
  }
  std::vector<std::pair<double, std::size_t>> found;
  std::vector<std::size_t> cells;
  for (std::int64_t r = 0;; ++r) {
    bool everything = true;
    for (int a = 0; a < grid.dimension; ++a)
      everything = everything && 2 * r + 1 >= (grid.periodic ? grid.count[a] : 2 * grid.count[a]);
    cells_around(grid, at, r, cells);
    found.clear();
    for (const std::size_t c : cells)
      for (std::size_t k = grid.start[c]; k < grid.start[c + 1]; ++k) {
        const std::size_t i = grid.order[k];
        found.emplace_back(domain.squared_distance(q, &centres[i * d]), i);
      }
    if (found.size() < size && !everything) continue;
    const auto nth = found.begin() + static_cast<std::ptrdiff_t>(std::min(size, found.size()));
    std::partial_sort(found.begin(), nth, found.end());
    const double reach = static_cast<double>(r) * side;
    if (everything || (found.size() >= size && found[size - 1].first <= reach * reach)) {
      out.clear();
      for (auto it = found.begin(); it != nth; ++it) out.push_back(it->second);
      std::sort(out.begin(), out.end());
      return;
    }
  }
}

// For the points `which` of `points`: P_Y(x)^2 with Y the centres `subset`, and the round-off
// allowance of that value (the points' bounds are bound_squared + allowance).
void subset_bounds(const AnyKernel& kernel, std::span<const double> centres,
                   std::span<const double> points, std::span<const std::size_t> which,
                   std::span<const std::size_t> subset, Eigen::VectorXd& upper) {
  const auto d = static_cast<std::size_t>(kernel.domain().dimension);
  const auto s = static_cast<Eigen::Index>(subset.size());
  const auto p = static_cast<Eigen::Index>(which.size());
  std::vector<double> y(subset.size() * d), x(which.size() * d);
  for (std::size_t k = 0; k < subset.size(); ++k)
    std::copy_n(&centres[subset[k] * d], d, &y[k * d]);
  for (std::size_t k = 0; k < which.size(); ++k) std::copy_n(&points[which[k] * d], d, &x[k * d]);
  const Eigen::VectorXd diagonal = kernel.diagonal(x);
  Eigen::MatrixXd gram(s, s);
  kernel.cross_into(y, y, gram);
  const Eigen::LLT<Eigen::MatrixXd> local(gram);
  if (local.info() != Eigen::Success) {
    for (Eigen::Index k = 0; k < p; ++k) {  // P(x)^2 <= k(x, x) whatever the centres
      auto& slot = upper[static_cast<Eigen::Index>(which[static_cast<std::size_t>(k)])];
      slot = std::min(slot, diagonal(k));
    }
    return;
  }
  Eigen::MatrixXd cross(p, s);
  kernel.cross_into(x, y, cross);
  Eigen::MatrixXd z = cross.transpose();
  local.matrixL().solveInPlace(z);
  // A backward-stable triangular solve: |z| is off by about s eps cond(L) |z|, and cond(L) is at
  // least the ratio of L's extreme diagonal entries; the allowance takes a thousand times that.
  const auto l_diagonal = local.matrixLLT().diagonal().cwiseAbs();
  const double condition = l_diagonal.maxCoeff() / l_diagonal.minCoeff();
  const double allowance = 1e3 * static_cast<double>(s) * eps * condition;
  for (Eigen::Index k = 0; k < p; ++k) {
    const double quadratic = z.col(k).squaredNorm();
    const double bound = std::max(0.0, diagonal(k) - quadratic);
    auto& slot = upper[static_cast<Eigen::Index>(which[static_cast<std::size_t>(k)])];
    slot = std::min(slot, bound + allowance * (diagonal(k) + quadratic));
  }
}

}  // namespace

BoundedPowerSup bounded_power_sup(const AnyKernel& kernel, std::span<const double> centres,
                                  std::span<const double> points,
                                  std::span<const std::size_t> always, const ExactPowerBlock& exact,
                                  bool search) {
  const Domain& domain = kernel.domain();
  const auto d = static_cast<std::size_t>(domain.dimension);
  const std::size_t m = domain.point_count(points);
  CellGrid grid = cells_of_one_point(domain, domain.point_count(centres));
  bucket(grid, domain, centres);
  Eigen::VectorXd upper = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(m),
                                                    std::numeric_limits<double>::infinity());
  BoundedPowerSup out;
  std::vector<bool> done(m, false);
  double best = -std::numeric_limits<double>::infinity();
  const auto evaluate = [&](std::vector<std::size_t> indices) {
    std::erase_if(indices, [&](std::size_t k) { return done[k]; });
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    if (indices.empty()) return;
    const std::size_t blocks = (indices.size() + exact_block - 1) / exact_block;
    Eigen::VectorXd power(static_cast<Eigen::Index>(indices.size()));
    Eigen::VectorXd norms(static_cast<Eigen::Index>(indices.size()));
    run_parts(blocks, [&](std::size_t b) {
      const std::size_t first = b * exact_block;
      const std::size_t count = std::min(exact_block, indices.size() - first);
      exact(std::span<const std::size_t>(indices).subspan(first, count),
            power.segment(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(count)),
            norms.segment(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(count)));
    });
    const auto start = static_cast<Eigen::Index>(out.evaluated.size());
    out.power_squared.conservativeResize(start + power.size());
    out.solution_norm_squared.conservativeResize(start + norms.size());
    out.power_squared.tail(power.size()) = power;
    out.solution_norm_squared.tail(norms.size()) = norms;
    for (const std::size_t k : indices) {
      done[k] = true;
      out.evaluated.push_back(k);
    }
    best = std::max(best, power.maxCoeff());
  };
  if (!search) {
    evaluate(std::vector<std::size_t>(always.begin(), always.end()));
    return out;
  }

  // Every point's bound, one subset per cell of the centre grid: the centres nearest the cell's
  // middle (any subset bounds P from above; near ones bound it tightly).
  {
    std::vector<std::vector<std::size_t>> by_cell(grid.cells());
    for (std::size_t k = 0; k < m; ++k) by_cell[grid.cell_of(domain, &points[k * d])].push_back(k);
    std::vector<std::size_t> occupied;
    for (std::size_t c = 0; c < by_cell.size(); ++c)
      if (!by_cell[c].empty()) occupied.push_back(c);
    const std::size_t per_part = 64;
    run_parts((occupied.size() + per_part - 1) / per_part, [&](std::size_t part) {
      std::vector<std::size_t> subset;
      std::array<double, Domain::max_dimension> middle{};
      for (std::size_t k = part * per_part; k < std::min(occupied.size(), (part + 1) * per_part);
           ++k) {
        const auto cell = grid.position(occupied[k]);
        for (int a = 0; a < grid.dimension; ++a)
          middle[a] = (static_cast<double>(cell[a]) + 0.5) * grid.side[a];
        nearest_centres(grid, domain, centres, middle.data(), cell_subset_size, subset);
        subset_bounds(kernel, centres, points, by_cell[occupied[k]], subset, upper);
      }
      check_cancelled();
    });
  }

  // The candidates, by decreasing bound (ties: lower index first).
  const auto candidates = [&] {
    std::vector<std::size_t> left;
    for (std::size_t k = 0; k < m; ++k)
      if (!done[k] && upper[static_cast<Eigen::Index>(k)] >= best) left.push_back(k);
    std::stable_sort(left.begin(), left.end(), [&](std::size_t a, std::size_t b) {
      return upper[static_cast<Eigen::Index>(a)] > upper[static_cast<Eigen::Index>(b)];
    });
    return left;
  };

  // The points asked for and the largest bounds first, then rounds of two blocks of the largest
  // bounds left until no bound reaches the best exact value; when many candidates are left, their
  // bounds are tightened once with larger subsets around each point.
  std::vector<std::size_t> first(always.begin(), always.end());
  {
    const auto left = candidates();
    first.insert(first.end(), left.begin(),
                 left.begin() + static_cast<std::ptrdiff_t>(std::min(left.size(), exact_block)));
  }
  evaluate(std::move(first));
  bool refined = false;
  for (;;) {
    auto left = candidates();
    if (left.empty()) break;
    if (!refined && left.size() > refine_above) {
      refined = true;
      out.refined = left.size();
      const std::size_t per_part = 16;
      run_parts((left.size() + per_part - 1) / per_part, [&](std::size_t part) {
        std::vector<std::size_t> subset;
        for (std::size_t k = part * per_part; k < std::min(left.size(), (part + 1) * per_part);
             ++k) {
          nearest_centres(grid, domain, centres, &points[left[k] * d], point_subset_size, subset);
          subset_bounds(kernel, centres, points, std::span<const std::size_t>(&left[k], 1), subset,
                        upper);
        }
        check_cancelled();
      });
      continue;
    }
    left.resize(std::min(left.size(), 2 * exact_block));
    evaluate(std::move(left));
    check_cancelled();
  }
  return out;
}

}  // namespace rkhs
