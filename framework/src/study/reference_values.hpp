#pragma once
// Internal to the study layer: reading the published values a `reference` expectation compares
// a metric with (rkhs/study/expectation.hpp, ReferenceSpec) from a CSV file below the data root.

#include <string>

#include "rkhs/study/expectation.hpp"

namespace rkhs::detail {

/// Fills spec.n, spec.values and spec.lines from the rows of spec.file (resolved below the data
/// root) that spec.where selects, in increasing n. The file has a header line naming its columns
/// ('#' lines and blank lines are skipped); it must have the columns `n`, spec.value_column and
/// every column of spec.where. Throws std::invalid_argument with "<file>:<line>:<column>: ..."
/// for a missing column, a row with another number of fields, an n that is not a positive whole
/// number or repeats, a value that is not a finite nonzero number, and `where` selecting no row
/// (naming the values the column has); the data root's own message for a file not found.
void read_reference_values(ReferenceSpec& spec);

}  // namespace rkhs::detail
