#pragma once
// The `csv` target (docs/roads.md): a measured road profile (arc length, elevation) from CSV.

#include <memory>
#include <string>
#include <string_view>

#include "rkhs/approx/target.hpp"
#include "rkhs/core/parameters.hpp"

namespace rkhs {

/// The `csv` target with `parameters` (resolved against the `csv` entry's parameters) built from
/// `text`, the contents of a CSV file, in place of the file that the `file` parameter names
/// (which is not looked for): `file_name` names the text in messages ("file_name:line:column:
/// ...") and the provenance is "sha256:" and the SHA-256 of `text`. The target reads its file
/// whole and parses it with this. Throws std::invalid_argument (ParameterError for a parameter)
/// for any problem with the parameters or the text.
std::unique_ptr<TargetFunction> csv_road_from_text(const ParameterSet& parameters,
                                                   const Domain& domain, std::string_view text,
                                                   const std::string& file_name);

}  // namespace rkhs
