#include "reference_values.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>

#include "rkhs/core/csv_text.hpp"
#include "rkhs/core/data_root.hpp"
#include "rkhs/core/printable.hpp"

namespace rkhs::detail {
namespace {

// Whether a field's text equals a `where` value as written: numerically when both are numbers
// ("50" selects "50.0"), else as text.
bool same_value(std::string_view field, const std::string& wanted) {
  const auto a = csv_text::parse_number(field), b = csv_text::parse_number(wanted);
  if (a && b) return *a == *b;
  return field == wanted;
}

}  // namespace

void read_reference_values(ReferenceSpec& spec) {
  const auto path = resolve_data_file(spec.file);
  // Every string the file or the study gives is echoed through printable().
  const std::string name = printable(path.string());
  auto in = csv_text::open_file(path, name);
  csv_text::Lines lines(in, name);
  auto error = [&](unsigned line, std::size_t column, const std::string& what) {
    return std::invalid_argument(fmt::format("{}:{}:{}: {}", name, line, column, what));
  };

  std::vector<std::string> header;
  unsigned header_line = 0;
  while (const auto next = lines.next()) {
    if (csv_text::blank_or_comment(*next)) continue;
    header_line = lines.number();
    for (const auto& field : csv_text::split(*next, ',')) header.emplace_back(field.text);
    break;
  }
  if (header.empty())
    throw error(lines.number() + 1, 1, "no header line: expected the names of the columns");
  auto column_of = [&](const std::string& column, std::string_view role) {
    const auto it = std::find(header.begin(), header.end(), column);
    if (it == header.end())
      throw error(header_line, 1,
                  fmt::format("no column '{}' ({}); the columns are {}", printable(column), role,
                              printable(fmt::format("{}", fmt::join(header, ", ")))));
    return static_cast<std::size_t>(it - header.begin());
  };
  const auto n_column = column_of("n", "the n of each value");
  const auto value_column = column_of(spec.value_column, "reference.value");
  std::vector<std::size_t> where_columns;
  for (const auto& [column, value] : spec.where)
    where_columns.push_back(column_of(column, "reference.where"));

  std::vector<std::set<std::string>> seen(spec.where.size());  // for "selects no row"
  struct Row {
    std::size_t n;
    double value;
    unsigned line;
  };
  std::vector<Row> rows;
  while (const auto next = lines.next()) {
    if (csv_text::blank_or_comment(*next)) continue;
    const auto fields = csv_text::split(*next, ',');
    const unsigned line = lines.number();
    if (fields.size() != header.size())
      throw error(line, 1,
                  fmt::format("{} field{}, expected {} as the header has (a field with a comma "
                              "cannot be read here)",
                              fields.size(), fields.size() == 1 ? "" : "s", header.size()));
    bool selected = true;
    for (std::size_t w = 0; w < spec.where.size(); ++w) {
      const auto& field = fields[where_columns[w]];
      seen[w].emplace(field.text);
      selected = selected && same_value(field.text, spec.where[w].second);
    }
    if (!selected) continue;
    const auto& n_field = fields[n_column];
    const auto n = csv_text::parse_number(n_field.text);
    if (!n || !(*n >= 1) || *n != std::floor(*n) || *n > 1e15)
      throw error(line, n_field.column,
                  fmt::format("n: '{}' is not a positive whole number", printable(n_field.text)));
    const auto& value_field = fields[value_column];
    const auto value = csv_text::parse_number(value_field.text);
    if (!value || !std::isfinite(*value) || *value == 0.0)
      throw error(line, value_field.column,
                  fmt::format("{}: '{}' is not a finite nonzero number (a ratio to it is taken)",
                              printable(spec.value_column), printable(value_field.text)));
    for (const auto& row : rows)
      if (row.n == static_cast<std::size_t>(*n))
        throw error(line, n_field.column,
                    fmt::format("n = {} again (line {} has it): one value per n", row.n, row.line));
    rows.push_back({static_cast<std::size_t>(*n), *value, line});
  }
  if (rows.empty()) {
    std::vector<std::string> columns;
    for (std::size_t w = 0; w < spec.where.size(); ++w)
      columns.push_back(
          printable(fmt::format("{}: {}", spec.where[w].first, fmt::join(seen[w], ", "))));
    throw error(header_line, 1,
                spec.where.empty() ? std::string("no row of values under the header")
                                   : fmt::format("reference.where selects no row (the file has {})",
                                                 fmt::join(columns, "; ")));
  }
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.n < b.n; });
  spec.n.clear(), spec.values.clear(), spec.lines.clear();
  for (const auto& row : rows) {
    spec.n.push_back(row.n);
    spec.values.push_back(row.value);
    spec.lines.push_back(row.line);
  }
}

}  // namespace rkhs::detail
