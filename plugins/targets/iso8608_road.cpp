// The `iso8608` target: random road profiles with the ISO 8608 displacement PSD (the formulas
// are in rkhs/targets/iso8608.hpp, the method and references in docs/roads.md).
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "rkhs/targets/iso8608.hpp"
#include "rkhs/core/random.hpp"
#include "rkhs/approx/target.hpp"

namespace rkhs {

double iso8608_class_level(char road_class) {
  if (road_class < 'A' || road_class > 'H')
    throw std::invalid_argument(
        fmt::format("ISO 8608 class '{}' does not exist (A to H)", road_class));
  return 16e-6 * std::pow(4.0, road_class - 'A');
}

double iso8608_psd(double n, double level, double waviness) {
  return level * std::pow(n / iso8608_reference_frequency, -waviness);
}

double Harmonics::evaluate(double s, double length) const {
  const double phase = 2 * std::numbers::pi * s / length;
  double sum = 0;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const double angle = phase * static_cast<double>(k[i]);
    sum += cosine[i] * std::cos(angle) + sine[i] * std::sin(angle);
  }
  return sum;
}

double Harmonics::slope(double s, double length) const {
  const double frequency = 2 * std::numbers::pi / length;
  const double phase = frequency * s;
  double sum = 0;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const double wavenumber = static_cast<double>(k[i]);
    const double angle = phase * wavenumber;
    sum += wavenumber * (sine[i] * std::cos(angle) - cosine[i] * std::sin(angle));
  }
  return frequency * sum;
}

Harmonics iso8608_harmonics(const Iso8608Settings& settings, double length) {
  const double dn = 1.0 / length;
  // Counted in floating point before anything is built: n_max L may be far beyond any size.
  const double first_real = std::max(1.0, std::ceil(settings.n_min * length - 1e-9));
  const double last_real = std::floor(settings.n_max * length + 1e-9);
  if (last_real - first_real + 1 > static_cast<double>(max_iso8608_harmonics))
    throw std::invalid_argument(fmt::format("{} harmonics (n_max L) is more than {}",
                                            format_real(last_real - first_real + 1),
                                            max_iso8608_harmonics));
  const auto first = static_cast<std::size_t>(first_real);
  const auto last = static_cast<std::size_t>(std::max(0.0, last_real));
  if (last < first)
    throw std::invalid_argument(
        fmt::format("no harmonic k / L (L = {} m) lies in [n_min, n_max] = [{}, {}] cycles/m",
                    format_real(length), format_real(settings.n_min), format_real(settings.n_max)));
  Harmonics out;
  Random random(hash_combine(hash64("iso8608"), settings.seed));
  for (std::size_t k = first; k <= last; ++k) {
    const double variance =
        iso8608_psd(static_cast<double>(k) * dn, settings.level, settings.waviness) * dn;
    out.k.push_back(k);
    if (settings.random_amplitudes) {
      out.cosine.push_back(std::sqrt(variance) * random.normal());
      out.sine.push_back(std::sqrt(variance) * random.normal());
    } else {
      // A cos(x + phi) = A cos(phi) cos(x) - A sin(phi) sin(x)
      const double amplitude = std::sqrt(2 * variance);
      const double phi = 2 * std::numbers::pi * random.uniform();
      out.cosine.push_back(amplitude * std::cos(phi));
      out.sine.push_back(-amplitude * std::sin(phi));
    }
  }
  return out;
}

namespace {

class Iso8608Road final : public TargetFunction {
 public:
  static PluginInfo info() {
    auto level = real_parameter("gd_n0", 0.0,
                                "Gd(n0) in m^3 at n0 = 0.1 cycles/m; 0: the class's geometric "
                                "mean (16e-6 4^(class - A)); a positive value overrides class",
                                0.0);
    auto n_min = real_parameter("n_min", 0.0, "lowest spatial frequency, cycles/m", 0.0);
    n_min.default_doc = "1 / L, the lowest harmonic";
    return {"iso8608",
            "random road profile with the ISO 8608 displacement PSD Gd(n0) (n/n0)^-w, a sum of "
            "harmonics n_k = k/L (periodic on the track) from a seed",
            {choice_parameter("class", "C", "ISO 8608 road class, A (very good) to H (very poor)",
                              {"A", "B", "C", "D", "E", "F", "G", "H"}),
             level, positive_parameter("waviness", 2.0, "w, the PSD's slope on log-log axes"),
             n_min, positive_parameter("n_max", 10.0, "highest spatial frequency, cycles/m"),
             choice_parameter("amplitudes", "deterministic",
                              "deterministic: sqrt(2 Gd dn) with random phases; random: Gaussian "
                              "coefficients (a Gaussian process sample)",
                              {"deterministic", "random"}),
             integer_parameter("seed", 1, "seed of the phases (and amplitudes)", 0,
                               std::int64_t{1} << 62)},
            {}};
  }

  Iso8608Road(const ParameterSet& p, const Domain& domain) : length_(domain.length) {
    require_track(domain, "iso8608");
    Iso8608Settings settings;
    settings.level =
        p.real("gd_n0") > 0 ? p.real("gd_n0") : iso8608_class_level(p.choice("class")[0]);
    settings.waviness = p.real("waviness");
    settings.n_min = p.real("n_min");
    settings.n_max = p.real("n_max");
    settings.random_amplitudes = p.choice("amplitudes") == "random";
    settings.seed = static_cast<std::uint64_t>(p.integer("seed"));
    if (settings.n_max < settings.n_min)
      throw ParameterError(
          "n_max", fmt::format("n_max ({}) is below n_min ({})", format_real(settings.n_max),
                               format_real(settings.n_min)));
    try {
      harmonics_ = iso8608_harmonics(settings, length_);
    } catch (const std::invalid_argument& e) {
      throw ParameterError("n_max", e.what());
    }
  }

  void evaluate(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m)
      out[m] = harmonics_.evaluate(points[m], length_);
  }
  /// The harmonics' sum differentiated term by term (Harmonics::slope).
  void derivative(std::span<const double> points, std::span<double> out) const override {
    for (std::size_t m = 0; m < points.size(); ++m) out[m] = harmonics_.slope(points[m], length_);
  }
  bool has_exact_derivative() const override { return true; }

 private:
  double length_;
  Harmonics harmonics_;
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_TARGET(rkhs::Iso8608Road)
