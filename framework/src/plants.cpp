// Built-in plants (quarter_car, linear), learning laws (gradient, rkhs) and the matrix syntax
// of study files.
#include <fmt/format.h>

#include <charconv>
#include <stdexcept>

#include "rkhs/lyapunov.hpp"
#include "rkhs/plant.hpp"

namespace rkhs {

PlantRegistry& plant_registry() {
  static PlantRegistry registry("plant");
  return registry;
}

LawRegistry& law_registry() {
  static LawRegistry registry("law");
  return registry;
}

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

namespace {

/// The quarter car of the paper's Section 5, state x = [x1', x1, x2', x2].
class QuarterCar final : public Plant {
 public:
  static PluginInfo info() {
    return {"quarter_car",
            "quarter-car suspension of the paper's Section 5, state [x1', x1, x2', x2]",
            {positive_parameter("m1", 0.5, "unsprung mass, kg"),
             positive_parameter("m2", 0.5, "sprung mass, kg"),
             positive_parameter("k1", 5e4, "tyre stiffness, N/m"),
             positive_parameter("k2", 3e4, "suspension stiffness, N/m"),
             positive_parameter("c2", 200.0, "suspension damping, N s/m"),
             boolean_parameter("paper_sign", false,
                               "use the paper's printed -c2/m2 in A[2][0] (Newton gives +c2/m2)")},
            {{"dimension", "4"}}};
  }
  explicit QuarterCar(const ParameterSet& p) : A_(4, 4), B_(4) {
    const double m1 = p.real("m1"), m2 = p.real("m2"), k1 = p.real("k1"), k2 = p.real("k2"),
                 c2 = p.real("c2");
    const double a20 = (p.boolean("paper_sign") ? -1.0 : 1.0) * c2 / m2;
    A_ << -c2 / m1, -(k1 + k2) / m1, c2 / m1, k2 / m1,  //
        1, 0, 0, 0,                                     //
        a20, k2 / m2, -c2 / m2, -k2 / m2,               //
        0, 0, 1, 0;
    B_ << k1 / m1, 0, 0, 0;
    require_hurwitz(A_);
  }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
};

/// x' = A x + B f with A and B written in the study file.
class LinearPlant final : public Plant {
 public:
  static PluginInfo info() {
    return {"linear",
            "x' = A x + B f with A (Hurwitz) and B given, e.g. A = \"-1 0; 0 -2\", B = \"1; 0\"",
            {text_parameter("A", "-1", "the d x d matrix A: rows separated by ';'"),
             text_parameter("B", "1", "the d x 1 matrix B: entries separated by ';'")},
            {}};
  }
  explicit LinearPlant(const ParameterSet& p) {
    A_ = parse_matrix(p.text("A"));
    const Eigen::MatrixXd b = parse_matrix(p.text("B"));
    if (A_.rows() != A_.cols())
      throw ParameterError("A",
                           fmt::format("A must be square, found {} x {}", A_.rows(), A_.cols()));
    if (b.cols() != 1 || b.rows() != A_.rows())
      throw ParameterError("B", fmt::format("B must be {} x 1 (one entry per row, separated by "
                                            "';'), found {} x {}",
                                            A_.rows(), b.rows(), b.cols()));
    B_ = b.col(0);
    require_hurwitz(A_);
  }
  const Eigen::MatrixXd& A() const noexcept override { return A_; }
  const Eigen::VectorXd& B() const noexcept override { return B_; }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd B_;
};

/// alpha' = Gamma^-1 [G^-1] phi(s) B^T P (x - xhat) with a scalar gain: the gradient law
/// (eq. a3) without G^-1, the rkhs law (eq. 4.2) with it.
template <bool UsesGramInverse>
class ScalarGainLaw final : public LearningLaw {
 public:
  static PluginInfo info() {
    if constexpr (UsesGramInverse)
      return {"rkhs", "alpha' = Gamma^-1 G^-1 phi(s) B^T P (x - xhat) (eq. 4.2)",
              {positive_parameter("gamma", 1e-3, "the gain Gamma")}, {}};
    else
      return {"gradient", "alpha' = Gamma^-1 phi(s) B^T P (x - xhat) (eq. a3)",
              {positive_parameter("gamma", 1e-3, "the gain Gamma")}, {}};
  }
  explicit ScalarGainLaw(const ParameterSet& p) : gain_(p.real("gamma")) {}
  bool uses_gram_inverse() const noexcept override { return UsesGramInverse; }
  double gain() const noexcept override { return gain_; }

 private:
  double gain_;
};
using GradientLaw = ScalarGainLaw<false>;
using RkhsLaw = ScalarGainLaw<true>;

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PLANT(rkhs::QuarterCar)
RKHS_REGISTER_PLANT(rkhs::LinearPlant)
RKHS_REGISTER_LAW(rkhs::GradientLaw)
RKHS_REGISTER_LAW(rkhs::RkhsLaw)
