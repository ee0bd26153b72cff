// The multiscale B-spline kernel against an independent evaluation of docs/model.md section 3.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <vector>

#include "kernel_test_support.hpp"
#include "rkhs/kernels/bspline.hpp"

namespace {

using rkhs::kernels::MultiscaleBSpline;
using rkhs::test::Given;

// N_p by the Cox-de Boor recursion on the knots 0..p+1 (independent of the kernel's pieces).
double cox_de_boor(int degree, double x) {
  if (degree == 0) return (x >= 0 && x < 1) ? 1.0 : 0.0;
  return (x * cox_de_boor(degree - 1, x) + (degree + 1 - x) * cox_de_boor(degree - 1, x - 1)) /
         degree;
}

struct Setting {
  int degree;
  double r;
  int n0;
  int levels;
};

// k(u, v) by the double sum of docs/model.md section 3, every spline of every level, dense.
double reference_kernel(const Setting& s, double length, bool periodic, double u, double v) {
  const double h0 = length / s.n0;
  double sum = 0;
  for (int j = 0; j <= s.levels; ++j) {
    const int cells = s.n0 << j;
    const double x = std::pow(2.0, j) * u / h0, y = std::pow(2.0, j) * v / h0;
    // Periodic: spline k wrapped modulo n_j, i.e. N_p(x - k + m n_j) summed over m.
    auto spline = [&](double z) {
      if (!periodic) return cox_de_boor(s.degree, z);
      double total = 0;
      for (int m = -2; m <= 2; ++m) total += cox_de_boor(s.degree, z + m * cells);
      return total;
    };
    const int first = periodic ? 0 : -s.degree;
    for (int k = first; k < cells; ++k)
      sum += std::pow(2.0, j * (1 - 2 * s.r)) * spline(x - k) * spline(y - k);
  }
  return sum;
}

Given given_of(const Setting& s) {
  return {{"degree", std::int64_t{s.degree}},
          {"r", s.r},
          {"n0", std::int64_t{s.n0}},
          {"J", std::int64_t{s.levels}}};
}

double sparse_dot(const rkhs::SparseFeatures& a, const rkhs::SparseFeatures& b) {
  std::map<int, double> left;
  for (std::size_t i = 0; i < a.size(); ++i) left[a.index[i]] += a.value[i];
  double sum = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    if (auto it = left.find(b.index[i]); it != left.end()) sum += it->second * b.value[i];
  return sum;
}

}  // namespace

TEST_CASE("cardinal B-splines take their known values", "[kernel][bspline]") {
  CHECK(MultiscaleBSpline::cardinal_bspline(0, 0.0) == 1.0);
  CHECK(MultiscaleBSpline::cardinal_bspline(0, 0.5) == 1.0);
  CHECK(MultiscaleBSpline::cardinal_bspline(0, 1.0) == 0.0);
  CHECK(MultiscaleBSpline::cardinal_bspline(1, 1.0) == 1.0);
  CHECK(MultiscaleBSpline::cardinal_bspline(1, 0.25) == 0.25);
  CHECK(MultiscaleBSpline::cardinal_bspline(2, 1.5) == Approx(0.75).epsilon(1e-15));
  CHECK(MultiscaleBSpline::cardinal_bspline(2, 1.0) == Approx(0.5).epsilon(1e-15));
  CHECK(MultiscaleBSpline::cardinal_bspline(3, 2.0) == Approx(2.0 / 3.0).epsilon(1e-15));
  CHECK(MultiscaleBSpline::cardinal_bspline(3, 1.0) == Approx(1.0 / 6.0).epsilon(1e-15));
  for (int p = 0; p <= 3; ++p) {
    INFO("degree " << p);
    CHECK(MultiscaleBSpline::cardinal_bspline(p, -0.1) == 0.0);
    CHECK(MultiscaleBSpline::cardinal_bspline(p, p + 1.0) == 0.0);
    CHECK(MultiscaleBSpline::cardinal_bspline(p, p + 1.5) == 0.0);
    double worst = 0;
    for (double x = -1.0; x <= 5.0; x += 1.0 / 64 + 1e-3)
      worst =
          std::max(worst, std::abs(MultiscaleBSpline::cardinal_bspline(p, x) - cox_de_boor(p, x)));
    CHECK(worst <= 1e-15);
  }
}

TEST_CASE("cardinal B-splines form a partition of unity", "[kernel][bspline]") {
  for (int p = 0; p <= 3; ++p) {
    double worst = 0;
    for (double x = 0.0; x < 7.0; x += 0.0173) {
      double sum = 0;
      for (int k = -4; k <= 8; ++k) sum += MultiscaleBSpline::cardinal_bspline(p, x - k);
      worst = std::max(worst, std::abs(sum - 1.0));
    }
    INFO("degree " << p);
    CHECK(worst <= 4e-16);
  }
}

TEST_CASE("each level of the feature map is a weighted partition of unity", "[kernel][bspline]") {
  for (bool periodic : {true, false}) {
    const rkhs::Domain domain{rkhs::test::track_length, periodic};
    for (int p = 0; p <= 3; ++p) {
      const Setting s{p, 1.25, 4, 5};
      const auto kernel = rkhs::test::make_kernel_of<MultiscaleBSpline>(given_of(s), domain);
      // Level j occupies feature indices [offset_j, offset_{j+1}).
      std::vector<int> offset{0};
      for (int j = 0; j <= s.levels; ++j)
        offset.push_back(offset.back() + (s.n0 << j) + (periodic ? 0 : p));
      REQUIRE(kernel.feature_count() == static_cast<std::size_t>(offset.back()));
      rkhs::SparseFeatures f;
      double worst = 0;
      for (double u : rkhs::test::scattered_points(200, domain.length)) {
        kernel.features(u, f);
        REQUIRE(f.size() == static_cast<std::size_t>((p + 1) * (s.levels + 1)));
        for (int j = 0; j <= s.levels; ++j) {
          double sum = 0;
          for (std::size_t i = 0; i < f.size(); ++i)
            if (f.index[i] >= offset[j] && f.index[i] < offset[j + 1]) sum += f.value[i];
          worst = std::max(worst, std::abs(sum / std::pow(2.0, 0.5 * j * (1 - 2 * s.r)) - 1.0));
        }
      }
      INFO((periodic ? "periodic" : "interval") << ", degree " << p);
      CHECK(worst <= 1e-14);
    }
  }
}

TEST_CASE("B-spline kernel and feature map equal the double sum of model.md", "[kernel][bspline]") {
  const std::vector<Setting> settings{{0, 0.75, 4, 3}, {1, 1.0, 4, 4}, {2, 2.0, 4, 3},
                                      {3, 3.0, 4, 2},  {1, 0.6, 2, 3}, {2, 1.5, 3, 2},
                                      {3, 2.5, 5, 3},  {3, 1.0, 1, 2}};
  for (bool periodic : {true, false}) {
    const rkhs::Domain domain{rkhs::test::track_length, periodic};
    for (const auto& s : settings) {
      if (periodic && s.n0 < s.degree + 1) continue;
      INFO((periodic ? "periodic" : "interval")
           << " degree " << s.degree << " r " << s.r << " n0 " << s.n0 << " J " << s.levels);
      const auto kernel = rkhs::test::make_kernel_of<MultiscaleBSpline>(given_of(s), domain);
      auto points = rkhs::test::scattered_points(40, domain.length);
      // Knots, the seam and the end points, where pieces meet. Degree 0 is discontinuous there
      // and its value at a knot depends on how u / h0 rounds (and at u = L on the interval the
      // kernel takes the left limit, the right-open N_0 would give 0), so it skips them.
      if (s.degree > 0) {
        for (double u :
             {0.0, domain.length / s.n0, 0.5 * domain.length, domain.length * (1 - 1e-16)})
          points.push_back(u);
        if (!periodic) points.push_back(domain.length);
      }
      rkhs::SparseFeatures fu, fv;
      double kernel_error = 0, feature_error = 0, scale = 0;
      for (double u : points) {
        kernel.features(u, fu);
        for (std::size_t i = 0; i < fu.size(); ++i) {
          CHECK(fu.index[i] >= 0);
          CHECK(static_cast<std::size_t>(fu.index[i]) < kernel.feature_count());
        }
        for (double v : points) {
          kernel.features(v, fv);
          const double expected = reference_kernel(s, domain.length, periodic, u, v);
          scale = std::max(scale, std::abs(expected));
          kernel_error = std::max(kernel_error, std::abs(kernel(u, v) - expected));
          feature_error = std::max(feature_error, std::abs(sparse_dot(fu, fv) - kernel(u, v)));
        }
      }
      REQUIRE(scale > 0);
      CHECK(kernel_error <= 1e-13 * scale);
      CHECK(feature_error <= 1e-14 * scale);
    }
  }
}

TEST_CASE("B-spline features of a point are distinct and the count matches", "[kernel][bspline]") {
  // n0 = degree + 1 on the periodic domain: every level-0 spline wraps around the whole track.
  const rkhs::Domain track{rkhs::test::track_length, true};
  const auto kernel =
      rkhs::test::make_kernel_of<MultiscaleBSpline>(given_of({3, 3.0, 4, 6}), track);
  CHECK(kernel.feature_count() == 4u * ((1u << 7) - 1));
  rkhs::SparseFeatures f;
  for (double u : rkhs::test::scattered_points(100, track.length)) {
    kernel.features(u, f);
    auto sorted = f.index;
    std::sort(sorted.begin(), sorted.end());
    CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
  }
  const rkhs::Domain interval{rkhs::test::track_length, false};
  const auto open =
      rkhs::test::make_kernel_of<MultiscaleBSpline>(given_of({2, 2.0, 3, 4}), interval);
  CHECK(open.feature_count() == 3u * ((1u << 5) - 1) + 5u * 2u);
}

TEST_CASE("B-spline features of a point that is not finite stay in range", "[kernel][bspline]") {
  // The state of a diverging adaptive trial (a Duffing plant with stiffness 2^62, property
  // fuzzer seed 54) reached the features as NaN: its cell index was undefined and the features
  // were written outside their storage (SIGSEGV). Such a point has the features of 0.
  for (const bool periodic : {true, false}) {
    const rkhs::Domain domain{rkhs::test::track_length, periodic};
    const auto kernel =
        rkhs::test::make_kernel_of<MultiscaleBSpline>(given_of({2, 2.0, 4, 2}), domain);
    rkhs::SparseFeatures at_zero, f;
    kernel.features(0.0, at_zero);
    for (const double u : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
      INFO("periodic " << periodic << ", u = " << u);
      kernel.features(u, f);
      CHECK(f.index == at_zero.index);
      CHECK(f.value == at_zero.value);
      for (const auto index : f.index)
        CHECK(static_cast<std::size_t>(index) < kernel.feature_count());
    }
  }
}

TEST_CASE("B-spline Gram matrices have the rank of the finest spline space", "[kernel][bspline]") {
  // The level spaces are nested, so k has rank n_J (periodic) or n_J + p (interval), well below
  // feature_count(): more centres than that give a singular Gram matrix.
  for (bool periodic : {true, false}) {
    const rkhs::Domain domain{rkhs::test::track_length, periodic};
    for (int p = 1; p <= 3; ++p) {
      const Setting s{p, static_cast<double>(p), 4, 2};
      auto kernel = rkhs::test::make_registered_kernel("bspline", given_of(s), domain);
      const int rank = (s.n0 << s.levels) + (periodic ? 0 : p);
      const auto centres =
          rkhs::test::scattered_points(static_cast<std::size_t>(2 * rank), domain.length);
      const Eigen::VectorXd lambda =
          Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(kernel->gram(centres)).eigenvalues();
      INFO((periodic ? "periodic" : "interval")
           << " degree " << p << ": eigenvalues " << lambda.transpose());
      const double zero =
          1e3 * static_cast<double>(lambda.size()) * rkhs::test::epsilon * lambda.maxCoeff();
      CHECK((lambda.array() > zero).count() == rank);
    }
  }
}

TEST_CASE("B-spline kernel metadata", "[kernel][bspline]") {
  const rkhs::Domain track{rkhs::test::track_length, true};
  const auto kernel =
      rkhs::test::make_kernel_of<MultiscaleBSpline>({{"degree", std::int64_t{2}}}, track);
  const auto props = kernel.properties();
  CHECK_FALSE(props.positive_definite);
  CHECK_FALSE(props.stationary);
  CHECK(props.periodic);
  CHECK(props.sobolev_order == 2.0);
  CHECK(props.support_radius == Approx(3 * track.length / 4));
  // Zero beyond the level-0 support on the interval, where the radius is below L.
  const rkhs::Domain interval{rkhs::test::track_length, false};
  const auto narrow = rkhs::test::make_kernel_of<MultiscaleBSpline>(
      {{"degree", std::int64_t{1}}, {"n0", std::int64_t{8}}}, interval);
  const double radius = narrow.properties().support_radius;
  CHECK(radius == Approx(2 * interval.length / 8));
  // Not stationary: points closer than the radius share a level-0 spline only if they are in
  // neighbouring cells; 0.5 h0 and 1.5 h0 share spline k = 0.
  const double h0 = interval.length / 8;
  CHECK(narrow(0.5 * h0, 0.5 * h0 + radius * 1.0001) == 0.0);
  CHECK(narrow(0.5 * h0, 1.5 * h0) > 0.0);
}
