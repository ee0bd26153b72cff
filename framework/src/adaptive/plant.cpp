// The matrix syntax of study files (parse_matrix). The plant and learning-law registries are
// defined with the other registries, in plugin/registry.cpp.
#include <fmt/format.h>

#include <charconv>
#include <stdexcept>

#include "rkhs/adaptive/plant.hpp"
#include "rkhs/adaptive/weight_matrix.hpp"

namespace rkhs {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::vector<double> parse_numbers(std::string_view text, std::string_view whole) {
  std::vector<double> out;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (std::isspace(static_cast<unsigned char>(text[i])) || text[i] == ','))
      ++i;
    if (i == text.size()) break;
    double value = 0;
    const char* begin = text.data() + i;
    auto [end, ec] = std::from_chars(begin, text.data() + text.size(), value);
    if (ec != std::errc() || end == begin)
      throw std::invalid_argument(fmt::format("in matrix \"{}\": '{}' is not a number", whole,
                                              text.substr(i, text.find_first_of(" ,", i) - i)));
    i += static_cast<std::size_t>(end - begin);
    out.push_back(value);
  }
  return out;
}

}  // namespace

Eigen::MatrixXd parse_matrix(std::string_view text, Eigen::Index size) {
  const auto body = trim(text);
  if (body == "identity" || body == "I") {
    if (size <= 0) throw std::invalid_argument("\"identity\" needs a known size here");
    return Eigen::MatrixXd::Identity(size, size);
  }
  if (body.starts_with("diag(") && body.ends_with(")")) {
    const auto values = parse_numbers(body.substr(5, body.size() - 6), text);
    if (values.empty()) throw std::invalid_argument(fmt::format("\"{}\": empty diagonal", text));
    return Eigen::Map<const Eigen::VectorXd>(values.data(),
                                             static_cast<Eigen::Index>(values.size()))
        .asDiagonal();
  }
  std::vector<std::vector<double>> rows;
  std::size_t start = 0;
  while (start <= body.size()) {
    const auto stop = std::min(body.find(';', start), body.size());
    rows.push_back(parse_numbers(body.substr(start, stop - start), text));
    start = stop + 1;
  }
  if (rows.empty() || rows.front().empty())
    throw std::invalid_argument(
        fmt::format("\"{}\" is not a matrix (rows separated by ';')", text));
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()),
                      static_cast<Eigen::Index>(rows[0].size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].size() != rows[0].size())
      throw std::invalid_argument(
          fmt::format("in matrix \"{}\": row {} has {} entries, row 1 has {}", text, r + 1,
                      rows[r].size(), rows[0].size()));
    for (std::size_t c = 0; c < rows[r].size(); ++c)
      out(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = rows[r][c];
  }
  return out;
}

WeightMatrix WeightMatrix::parse(std::string_view text) {
  WeightMatrix out;
  out.text_ = std::string(text);
  const auto body = trim(text);
  if (body != "identity" && body != "I") out.given_ = parse_matrix(text);
  return out;
}

Eigen::MatrixXd WeightMatrix::for_dimension(Eigen::Index d, std::string_view name) const {
  if (given_.size() == 0) return Eigen::MatrixXd::Identity(d, d);
  if (given_.rows() != d || given_.cols() != d)
    throw std::invalid_argument(fmt::format("{} is {} x {}, this plant needs {} x {}", name,
                                            given_.rows(), given_.cols(), d, d));
  return given_;
}

}  // namespace rkhs
