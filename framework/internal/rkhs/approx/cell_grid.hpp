#pragma once
// Points of a domain bucketed in a uniform grid of cells: the sparse path's neighbour searches
// (rkhs/approx/sparse_gram.hpp). Two geometries: cells at least a support radius wide, so that
// two points closer than the radius lie in the same or in neighbouring cells (the sparse Gram
// and cross matrices), and cells of about one point each (the nearest centres of
// bounded_power_sup). Cells are numbered with the first axis fastest; on a periodic domain the
// neighbours of a cell wrap across the seam.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "rkhs/core/domain.hpp"

namespace rkhs {

struct CellGrid {
  using Position = std::array<std::int64_t, Domain::max_dimension>;

  int dimension = 1;
  bool periodic = false;
  Position count{1, 1, 1};                                  ///< cells per axis
  std::array<double, Domain::max_dimension> side{1, 1, 1};  ///< a cell's width per axis
  std::vector<std::size_t> start;  ///< after bucket(): cell c holds order[start[c] .. start[c + 1])
  std::vector<std::size_t> order;  ///< point indices, by cell, increasing within a cell
  std::vector<double> coordinates;  ///< the points' coordinates in `order`

  std::size_t cells() const;
  /// The cell of coordinate `x` on `axis` (wrapped when periodic, clamped to the grid).
  std::int64_t axis_cell(const Domain& domain, double x, int axis) const;
  /// The cell holding the point `x` (dimension coordinates).
  std::size_t cell_of(const Domain& domain, const double* x) const;
  /// Cell c's position on each axis.
  Position position(std::size_t c) const;
};

/// floor(extent / radius) cells per axis (at least one), fewer when there would be more cells
/// than 4 `points` + 64 (the cells stay at least `radius` wide).
CellGrid cells_at_least(const Domain& domain, double radius, std::size_t points);

/// Cells of about one point each for `points` points spread over `domain`: on each axis
/// round(extent / spacing) cells (at least one), spacing = (volume / points)^(1/d).
CellGrid cells_of_one_point(const Domain& domain, std::size_t points);

/// Buckets `points` into `grid` (whose geometry is set), stably.
void bucket(CellGrid& grid, const Domain& domain, std::span<const double> points);

/// The cells within `reach` cells of `at` on every axis (across the seam when periodic), each
/// once, in increasing order; reach 1 gives a cell's neighbours, itself included.
void cells_around(const CellGrid& grid, const CellGrid::Position& at, std::int64_t reach,
                  std::vector<std::size_t>& out);

/// The coordinates of the points of cell `c` (after bucket()).
std::span<const double> cell_points(const CellGrid& grid, std::size_t c);

/// The indices (into the bucketed point set) of the points of cell `c`, in `cell_points` order.
std::span<const std::size_t> cell_indices(const CellGrid& grid, std::size_t c);

}  // namespace rkhs
