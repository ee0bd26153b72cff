// The expression target: f(s) written in the study file (rkhs/core/expression.hpp).
#include "rkhs/core/expression.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "rkhs/approx/target.hpp"

namespace rkhs {
namespace {

/// f(s) = the expression `f`, a function of the arc length s (metres) that may read the
/// constants L (the domain's length), pi, and the target's own parameters: every other key of
/// its [[target]] table, a number (a list of numbers is an axis of the grid, like any
/// parameter's list):
///
///   [[target]]
///   name = "expression"
///   f = "a * sin(2 * pi * k * s / L)"
///   a = 2
///   k = [1, 2, 3]
///
/// f is evaluated on the domain: [0, L) on a closed track, where the expression must itself be
/// periodic (f(L) = f(0), and f'(L) = f'(0) for a road without a kink at s = 0; the target notes
/// it when the study is loaded, and reports s = 0 as a kink), [0, L] on an interval.
///
/// Refused when the study is loaded (ParameterError, at the key it names): f missing, a mistake
/// in f (syntax, unknown name, wrong argument count: the position in f, what was found there and
/// what was expected), a parameter named s, L, pi or after a function, a parameter f does not
/// read, and an f that is not finite at one of `check_points` uniform points of the domain. A
/// value that is not finite anywhere else fails the trial that meets it (evaluate() and
/// derivative() throw std::domain_error, naming s and the value).
///
/// f'(s) is a difference quotient of order 4 (derivative()).
///
/// On a domain of d = 2 or 3 (a box or a torus, core/domain.hpp) f is a function of the point
/// x = (x1, ..., xd) and reads the constants L1, ..., Ld (the extents of the axes) instead of
/// s and L:
///
///   f = "sin(2 * pi * x1 / L1) * cos(2 * pi * x2 / L2)"
///
/// It is checked for finite values at about `check_points` grid points of the domain (not for
/// periodicity on a torus); derivative() is defined on tracks and intervals only (d = 1).
class ExpressionTarget final : public TargetFunction {
 public:
  /// The step h of derivative(), metres: 2^-14, about 6.1e-5 (a power of two, so that s + k h
  /// is exact for most s).
  static constexpr double step = 0x1p-14;
  /// The points of the domain f is checked at when it is built.
  static constexpr std::size_t check_points = 1024;

  static PluginInfo info() {
    auto f = text_parameter(
        "f", "",
        "f(s), an expression of the arc length s, e.g. \"2 * sin(2 * pi * s / L)\"; it may read "
        "L (the domain's length), pi and the target's own parameters (docs/study-files.md); in "
        "d = 2, 3 an expression of x1, ..., xd reading L1, ..., Ld");
    f.default_doc = "none: required";
    return {"expression",
            "f(s) written in the study file as an expression of the arc length s",
            {f},
            {{"derivative",
              "4th-order central difference, h = 2^-14 m (one-sided at an interval's ends)"}},
            real_parameter(
                "<name>", 0.0,
                "any other key: a constant f reads by that name, e.g. a = 2 (a list is an axis)")};
  }

  ExpressionTarget(const ParameterSet& p, const Domain& domain)
      : domain_(domain), expression_(compile(p, domain)) {
    check_finite_and_periodic();
  }

  void evaluate(std::span<const double> points, std::span<double> out) const override {
    expression_.evaluate(points, out);
    const auto d = static_cast<std::size_t>(domain_.dimension);
    for (std::size_t m = 0; m < out.size(); ++m)
      if (!std::isfinite(out[m])) throw not_finite(points.subspan(m * d, d), out[m]);
  }

  /// f'(s) by the 5-point central difference
  ///   (f(s - 2h) - 8 f(s - h) + 8 f(s + h) - f(s + 2h)) / (12 h),   h = step = 2^-14 m,
  /// and on an interval, where s - 2h < 0 or s + 2h > L, by the one-sided 5-point difference
  ///   -+(25 f(s) - 48 f(s -+ h) + 36 f(s -+ 2h) - 16 f(s -+ 3h) + 3 f(s -+ 4h)) / (12 h),
  /// so that f is evaluated on [0, L] only. (On a closed track the central difference near 0
  /// and L reads the expression just outside [0, L), which a periodic expression continues.)
  ///
  /// Error: Taylor's theorem with remainder gives the truncation error h^4 |f^(5)(xi)| / 30
  /// (central) and h^4 |f^(5)(xi)| / 5 (one-sided) for some xi between the nodes; f evaluated
  /// to relative accuracy delta (about the unit roundoff u = 2^-53 for a short expression) adds
  /// at most (sum of |weights|) delta max|f| / (12 h): 1.5 delta max|f| / h (central),
  /// 10.7 delta max|f| / h (one-sided). For f with features of length l (|f^(5)| <= |f| / l^5)
  /// and relative to the slope scale |f| / l, the total is
  ///   (h / l)^4 / 30 + 1.5 delta l / h   (central),  (h / l)^4 / 5 + 10.7 delta l / h (one-sided),
  /// with delta = u below 5e-11 (central) and 3e-10 (one-sided) for every l from 1 cm to 10 m
  /// (the default derivative's h = 1e-6 m central difference: 3e-9). The nodes s + k h are
  /// rounded to doubles: exact for most s (h is a power of two; not within 4h below a power of
  /// two), and always within u |s + k h|, which adds at most 1.5 u (|s| + 2h) |f'| / h
  /// (central; 10.7 u (|s| + 4h) |f'| / h one-sided): 2.7e-11 |f'| per 10 m of s.
  void derivative(std::span<const double> points, std::span<double> out) const override {
    if (domain_.dimension != 1)
      throw std::logic_error("the expression target's derivative is defined for d = 1 only");
    for (std::size_t m = 0; m < points.size(); ++m) out[m] = slope_at(points[m]);
  }

  /// Where the closed track's seam is not smooth (f(L) != f(0) or f'(L) != f'(0)): s = 0.
  void list_kink_points(const std::function<void(double)>& sink) const override {
    if (!seam_note_.empty()) sink(0.0);
  }
  void list_notes(const std::function<void(std::string_view)>& sink) const override {
    if (!seam_note_.empty()) sink(seam_note_);
  }

 private:
  // The variables f reads: s in d = 1, x1..xd otherwise.
  static std::vector<std::string> variables(const Domain& domain) {
    if (domain.dimension == 1) return {"s"};
    std::vector<std::string> out;
    for (int a = 1; a <= domain.dimension; ++a) out.push_back("x" + std::to_string(a));
    return out;
  }
  // The domain's constants: L in d = 1, L1..Ld otherwise; then pi.
  static std::vector<NamedValue> domain_constants(const Domain& domain) {
    std::vector<NamedValue> out;
    if (domain.dimension == 1) {
      out.push_back({"L", domain.length});
    } else {
      for (int a = 0; a < domain.dimension; ++a)
        out.push_back({"L" + std::to_string(a + 1), domain.extent(a)});
    }
    out.push_back({"pi", std::numbers::pi});
    return out;
  }

  // The expression of `p`, with s (or x1..xd) the variables and L (or L1..Ld), pi and the
  // user's parameters constants.
  static Expression compile(const ParameterSet& p, const Domain& domain) {
    const std::string& text = p.text("f");
    if (!p.given("f"))
      throw ParameterError("f", domain.dimension == 1
                                    ? "parameter 'f' is required: f(s) as an expression of the "
                                      "arc length s, e.g. f = \"2 * sin(2 * pi * s / L)\""
                                    : "parameter 'f' is required: f(x1, ..., xd) as an expression "
                                      "of the point, e.g. f = \"sin(2 * pi * x1 / L1) * x2\"");
    const auto names = variables(domain);
    std::vector<NamedValue> constants = domain_constants(domain);
    const std::size_t own_constants = constants.size();
    for (const auto& entry : p.values()) {
      const std::string& name = entry.first;  // a named reference: clang 14 cannot capture a
                                              // structured binding in the lambda below
      if (name == "f") continue;
      const bool is_variable = std::find(names.begin(), names.end(), name) != names.end();
      const auto taken = std::find_if(constants.begin(), constants.begin() + own_constants,
                                      [&](const NamedValue& c) { return c.name == name; });
      if (is_variable || taken != constants.begin() + own_constants)
        throw ParameterError(name,
                             fmt::format("parameter name '{}' is taken: f reads {} as {}; name the "
                                         "parameter otherwise",
                                         name, name,
                                         name == "s"   ? "the arc length"
                                         : is_variable ? "a coordinate of the point"
                                         : name == "L" ? "the domain's length"
                                         : name == "pi" ? "3.14159..."
                                                        : "an extent of the domain"));
      if (const auto why = Expression::check_name(name); !why.empty())
        throw ParameterError(name, fmt::format("parameter name '{}' {}: f could not read it; name "
                                               "the parameter otherwise",
                                               name, why));
      constants.push_back({name, p.real(name)});
    }
    try {
      Expression expression(text, names, constants);
      for (std::size_t c = own_constants; c < constants.size(); ++c)
        if (!expression.uses(constants[c].name))
          throw ParameterError(constants[c].name,
                               fmt::format("parameter '{}' is not read by f = \"{}\": use it in "
                                           "f or remove it",
                                           constants[c].name, text));
      return expression;
    } catch (const ExpressionError& e) {
      const auto where = e.position() >= text.size()
                             ? std::string("at the end of")
                             : fmt::format("at character {} of", e.position() + 1);
      // A coordinate of another dimension (s on a domain in R^d, x or x1 on a track) names the
      // variables there are; any other name f reads that the table does not give is most
      // likely a parameter left out.
      const std::string& unknown = e.unknown_name();
      const bool coordinate_of_another_dimension =
          domain.dimension == 1
              ? unknown == "x" || (unknown.size() >= 2 && unknown[0] == 'x' &&
                                   std::isdigit(static_cast<unsigned char>(unknown[1])))
              : unknown == "s" || unknown == "x";
      const auto hint =
          unknown.empty() ? std::string()
          : coordinate_of_another_dimension
              ? (domain.dimension == 1
                     ? fmt::format(" ({} is not a variable on this track (d = 1): f reads its "
                                   "point as s, the arc length)",
                                   unknown)
                     : fmt::format(" ({} is not a variable on this domain (d = {}): f reads its "
                                   "point as {})",
                                   unknown, domain.dimension, fmt::join(names, ", ")))
              : fmt::format(
                    " (a constant of the target's own is a key of its [[target]] table, e.g. "
                    "{} = 1)",
                    unknown);
      throw ParameterError("f", fmt::format("{} f = \"{}\": found {}, expected {}{}", where, text,
                                            e.found(), e.expected(), hint));
    }
  }

  std::domain_error not_finite(std::span<const double> point, double value) const {
    std::string where;
    if (point.size() == 1) {
      where = "s = " + format_real(point[0]);
    } else {
      for (std::size_t a = 0; a < point.size(); ++a)
        where += fmt::format("{}x{} = {}", a ? ", " : "", a + 1, format_real(point[a]));
    }
    return std::domain_error(fmt::format(
        "f = \"{}\" is {} at {}: f must be finite on the domain (look for a logarithm or "
        "square root of a negative number, or a division by zero)",
        expression_.text(), format_real(value), where));
  }

  // f at the check points (a ParameterError for a value that is not finite there), and on a
  // closed track the seam: f and f' at L against 0.
  void check_finite_and_periodic() {
    const auto points = domain_.uniform_points(check_points);
    const auto d = static_cast<std::size_t>(domain_.dimension);
    std::vector<double> values(domain_.point_count(points));
    expression_.evaluate(points, values);
    double scale = 0;
    for (std::size_t m = 0; m < values.size(); ++m) {
      if (!std::isfinite(values[m]))
        throw ParameterError(
            "f", fmt::format("{} (found when f was checked at {} uniform points of the domain)",
                             not_finite(std::span<const double>(points).subspan(m * d, d),
                                        values[m])
                                 .what(),
                             values.size()));
      scale = std::max(scale, std::abs(values[m]));
    }
    if (!domain_.periodic || d > 1) return;
    const double length = domain_.length;
    const double start = values.front(), end = expression_(std::span<const double>(&length, 1));
    // Values to 1e-9 of f's scale; slopes to 1e-6 of the slope scale, far above the difference
    // quotient's error (above) and far below a kink anyone would mean.
    if (!(std::abs(end - start) <= 1e-9 * scale)) {
      seam_note_ = fmt::format(
          "f = \"{}\" is not periodic on the closed track: f(L) = {} and f(0) = {} (L = {}), so "
          "the road jumps at s = 0; write a periodic expression, e.g. sin(2 * pi * k * s / L) "
          "with k whole",
          expression_.text(), format_real(end), format_real(start), format_real(length));
      return;
    }
    // The slopes on either side of the seam: into the lap at 0, out of it at L (a central
    // difference there would average the two).
    const double slope_start = slope_at(0.0, Stencil::forward);
    const double slope_end = slope_at(length, Stencil::backward);
    double slope_scale = 0;
    for (std::size_t m = 0; m < points.size(); m += 8)
      slope_scale = std::max(slope_scale, std::abs(slope_at(points[m])));
    slope_scale = std::max({slope_scale, std::abs(slope_start), std::abs(slope_end)});
    if (!(std::abs(slope_end - slope_start) <= 1e-6 * slope_scale))
      seam_note_ = fmt::format(
          "f = \"{}\" has a kink at s = 0 on the closed track: f'(L) = {:.6g} and f'(0) = {:.6g} "
          "(L = {}); s = 0 is reported as a kink",
          expression_.text(), slope_end, slope_start, format_real(length));
  }

  enum class Stencil { central, forward, backward };

  // The difference quotient of derivative(): one-sided where an interval would be left.
  double slope_at(double s) const {
    if (!domain_.periodic && s - 2 * step < 0) return slope_at(s, Stencil::forward);
    if (!domain_.periodic && s + 2 * step > domain_.length) return slope_at(s, Stencil::backward);
    return slope_at(s, Stencil::central);
  }

  // The 5-point difference quotient `stencil` at s (derivative() gives the formulas).
  double slope_at(double s, Stencil stencil) const {
    const double h = step;
    std::array<double, 5> nodes{}, values{};
    if (stencil == Stencil::central) {
      nodes = {s - 2 * h, s - h, s + h, s + 2 * h, s};
      evaluate(std::span<const double>(nodes.data(), 4), std::span<double>(values.data(), 4));
      return (values[0] - 8 * values[1] + 8 * values[2] - values[3]) / (12 * h);
    }
    const double direction = stencil == Stencil::forward ? 1.0 : -1.0;
    for (int k = 0; k < 5; ++k) nodes[k] = s + direction * k * h;
    evaluate(nodes, values);
    return direction *
           (-25 * values[0] + 48 * values[1] - 36 * values[2] + 16 * values[3] - 3 * values[4]) /
           (12 * h);
  }

  Domain domain_;
  Expression expression_;
  std::string seam_note_;  // empty: smooth at the seam, or an interval
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_TARGET(rkhs::ExpressionTarget)
