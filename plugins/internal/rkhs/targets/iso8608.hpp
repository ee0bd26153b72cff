#pragma once
// Random road profiles after ISO 8608:2016 (the `iso8608` target; docs/roads.md).
//
// The displacement power spectral density (one-sided, m^3 = m^2 per cycle/m) is
//     Gd(n) = Gd(n0) (n / n0)^-w,   n0 = 0.1 cycles/m,   w = 2 (waviness)
// with the class's Gd(n0) (geometric mean of the class band, ISO 8608 Table 1). On a track of
// length L the profile is a sum of harmonics at n_k = k / L (so it is periodic on the track):
//     z(s) = sum_k A_k cos(2 pi n_k s + phi_k),   A_k = sqrt(2 Gd(n_k) dn),   dn = 1 / L,
// phi_k uniform in [0, 2 pi) from the seed ("deterministic" amplitudes), or
//     z(s) = sum_k a_k cos(2 pi n_k s) + b_k sin(2 pi n_k s),   a_k, b_k ~ N(0, Gd(n_k) dn)
// ("random" amplitudes: a sample of the stationary Gaussian process with that PSD).

#include <cstdint>
#include <string_view>
#include <vector>

namespace rkhs {

/// Reference spatial frequency of ISO 8608, cycles/m.
inline constexpr double iso8608_reference_frequency = 0.1;

/// Gd(n0) of class 'A'..'H' in m^3: 16e-6 * 4^(class - 'A') (the geometric mean of the class
/// band). Throws std::invalid_argument for any other letter.
double iso8608_class_level(char road_class);

/// Gd(n) = level (n / n0)^-waviness, m^3.
double iso8608_psd(double n, double level, double waviness);

struct Iso8608Settings {
  double level = 256e-6;  ///< Gd(n0), m^3
  double waviness = 2.0;  ///< w
  double n_min = 0.0;     ///< lowest spatial frequency, cycles/m (0: 1 / L)
  double n_max = 10.0;    ///< highest spatial frequency, cycles/m
  bool random_amplitudes = false;
  std::uint64_t seed = 1;
};

/// A realisation as harmonics: z(s) = sum_k cos_k cos(2 pi k s / L) + sin_k sin(2 pi k s / L).
struct Harmonics {
  std::vector<std::size_t> k;  ///< harmonic numbers (n_k = k / L), increasing
  std::vector<double> cosine, sine;
  double evaluate(double s, double length) const;
  /// dz/ds = sum (2 pi k / L) (sin_k cos(2 pi k s / L) - cos_k sin(2 pi k s / L)).
  double slope(double s, double length) const;
};

/// The most harmonics one realisation may have.
inline constexpr std::size_t max_iso8608_harmonics = 100000;

/// The harmonics of one realisation on a track of `length` metres. Deterministic for a given
/// seed. Throws std::invalid_argument when no harmonic k / L lies in [n_min, n_max], or when
/// more than max_iso8608_harmonics do (checked before any is built).
Harmonics iso8608_harmonics(const Iso8608Settings& settings, double length);

}  // namespace rkhs
