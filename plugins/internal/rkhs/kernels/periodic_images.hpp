#pragma once
// Periodisation of a stationary kernel by images, shared by the stationary built-in kernels.
//
// On the periodic domain [0, L) a stationary kernel k0(|x - y|) on the line becomes
//     k(s, t) = sum_{m in Z} k0(|d + m L|),   d = s - t reduced to [-L/2, L/2].
// This is positive definite whenever k0 is (its Fourier coefficients are samples of the Fourier
// transform of k0), unlike k0 of the distance along the circle. The series is truncated to
// |m| <= M with M chosen once per kernel instance.

#include <cmath>
#include <limits>

namespace rkhs::kernels {

/// Truncation tolerance of image sums, relative to k0(0) (<= k(x, x)).
inline constexpr double image_tolerance = 1e-16;

/// The smallest M such that the images with |m| > M contribute less than
/// `relative_tolerance * k0(0)` for every |d| <= L/2.
///
/// `profile(r)`, r >= 0, must be positive at 0, non-increasing, and log-concave where positive
/// (true for the Gaussian, the Matern profiles with half-integer nu and Wendland's functions).
/// Image |m| > M lies at distance >= (|m| - 1/2) L, so the omitted part is at most
///     2 sum_{m > M} t_m,  t_m = profile((m - 1/2) L),
/// and log-concavity makes the ratios t_{m+1}/t_m non-increasing, hence
///     sum_{m > M} t_m <= t_{M+1} / (1 - t_{M+2}/t_{M+1}).
/// Throws nothing; returns `max_images` if the bound is not reached before it.
template <class Profile>
int image_count(const Profile& profile, double length, double relative_tolerance,
                int max_images = 1 << 20) {
  const double target = relative_tolerance * profile(0.0);
  for (int count = 0; count < max_images; ++count) {
    const double first = profile((count + 0.5) * length);
    if (first == 0.0) return count;
    const double second = profile((count + 1.5) * length);
    const double ratio = second / first;
    if (ratio < 1.0 && 2.0 * first / (1.0 - ratio) <= target) return count;
  }
  return max_images;
}

/// sum_{m=-images}^{images} slope(d + m L), smallest terms first: d/dd of the image sum when
/// `slope(r)` is d/dr of profile(|r|) (an odd function of the signed distance r).
template <class Slope>
inline double sum_of_image_slopes(const Slope& slope, double d, double length, int images) {
  double sum = 0.0;
  for (int m = images; m >= 1; --m) sum += slope(d + m * length) + slope(d - m * length);
  return sum + slope(d);
}

/// sum_{m=-images}^{images} profile(|d + m L|), smallest terms first.
template <class Profile>
inline double sum_of_images(const Profile& profile, double d, double length, int images) {
  double sum = 0.0;
  for (int m = images; m >= 1; --m)
    sum += profile(std::abs(d + m * length)) + profile(std::abs(d - m * length));
  return sum + profile(std::abs(d));
}

}  // namespace rkhs::kernels
