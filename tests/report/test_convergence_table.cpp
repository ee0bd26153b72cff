// Tests of the console convergence table (rkhs/report/convergence_table.hpp): whole-output golden
// strings, so any change of layout shows up here.

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "rkhs/report/convergence_table.hpp"
#include "rkhs/rates/rates.hpp"

namespace {

struct Series {
  std::vector<rkhs::TableRow> rows;
  std::vector<double> x, y;
  void add(double abscissa, double value, bool flagged = false) {
    rows.push_back({abscissa, value, flagged});
    x.push_back(abscissa);
    y.push_back(value);
  }
};

}  // namespace

TEST_CASE("convergence table of an exact n^-1.5 series, one value flagged", "[rates]") {
  // 10^-1.5 = 3.1623e-2, 20^-1.5 = 1.1180e-2, 40^-1.5 = 3.9528e-3, 80^-1.5 = 1.3975e-3.
  Series s;
  for (double n : {10.0, 20.0, 40.0}) s.add(n, std::pow(n, -1.5));
  s.add(80.0, std::pow(80.0, -1.5), true);
  const auto fit = rkhs::fit_power_law(s.x, s.y);
  REQUIRE(fit);
  const std::string expected =
      "l2_error, group gaussian/eps=2\n"
      " n   l2_error    rate\n"
      "10  3.162e-02       -\n"
      "20  1.118e-02   -1.50\n"
      "40  3.953e-03   -1.50\n"
      "80  1.398e-03*  -1.50\n"
      "fitted rate: -1.50 ± 0.00 (95% CI [-1.50, -1.50], R² = 1.000, 4 points)\n"
      "* value flagged: at the round-off floor or from a singular Gram matrix\n";
  CHECK(rkhs::format_convergence_table("l2_error", "gaussian/eps=2", "n", s.rows, fit) == expected);
}

TEST_CASE("convergence table without flags, with a noisy fit and an exclusion note", "[rates]") {
  Series s;
  s.add(100, 2.0e-2);
  s.add(200, 6.0e-3);
  s.add(400, 3.0e-3);
  s.add(800, 0.0);  // e.g. an error that underflowed: excluded from rates and fit
  s.add(1600, 1.0e-4);
  const auto fit = rkhs::fit_power_law(s.x, s.y);
  REQUIRE(fit);
  // ln-ln slope through (100, 2e-2), (200, 6e-3), (400, 3e-3), (1600, 1e-4):
  // slope -1.894879272 (computed independently); the fit is checked by value, the layout by
  // string.
  CHECK(fit->rate == Approx(-1.894879272).margin(1e-8));
  const std::string table =
      rkhs::format_convergence_table("sup_error", "wendland", "n", s.rows, fit, "unused");
  const std::string head =
      "sup_error, group wendland\n"
      "   n  sup_error   rate\n"
      " 100  2.000e-02      -\n"
      " 200  6.000e-03  -1.74\n"
      " 400  3.000e-03  -1.00\n"
      " 800  0.000e+00      -\n"
      "1600  1.000e-04      -\n"
      "fitted rate: ";
  CHECK(table.substr(0, head.size()) == head);
  CHECK(table.find("4 points)\nnote: excluded 1 of 5 points: 1 with zero or negative value\n") !=
        std::string::npos);
  CHECK(table.find("unused") == std::string::npos);  // no flags, no legend
  CHECK(table.find('*') == std::string::npos);
}

TEST_CASE("convergence table footers when the fit is exponential, exact or impossible", "[rates]") {
  SECTION("exponential model, fill-distance-free axis name and 3 significant digits") {
    Series s;
    for (double n : {4.0, 8.0, 12.0}) s.add(n, std::exp(-0.3 * n));
    const auto fit = rkhs::fit_exponential(s.x, s.y);
    REQUIRE(fit);
    const auto table = rkhs::format_convergence_table("l2_error", "gaussian", "n", s.rows, fit);
    CHECK(table.find("\nfitted rate (exponential in n): -0.300 ± 0.000 (95% CI [-0.300, "
                     "-0.300], R² = 1.000, 3 points)\n") != std::string::npos);
  }
  SECTION("two points") {
    Series s;
    s.add(10, 1.0);
    s.add(40, 1.0 / 64.0);
    const auto table =
        rkhs::format_convergence_table("l2_error", "g", "n", s.rows, rkhs::fit_power_law(s.x, s.y));
    CHECK(table ==
          "l2_error, group g\n"
          " n   l2_error   rate\n"
          "10  1.000e+00      -\n"
          "40  1.562e-02  -3.00\n"
          "fitted rate: -3.00 (2 points, no confidence interval)\n"
          "note: only 2 points: slope exact, no standard error or confidence interval\n");
  }
  SECTION("no fit possible") {
    Series s;
    s.add(0.5, 3.0e-3, true);
    s.add(0.25, std::numeric_limits<double>::quiet_NaN());
    const auto fit = rkhs::fit_power_law(s.x, s.y);
    REQUIRE_FALSE(fit);
    CHECK(rkhs::format_convergence_table("power_function_sup", "bspline", "h", s.rows, fit,
                                         "singular Gram matrix") ==
          "power_function_sup, group bspline\n"
          "   h  power_function_sup   rate\n"
          " 0.5           3.000e-03*     -\n"
          "0.25                 nan      -\n"
          "fitted rate: not available (1 of 2 points have a finite, positive value; a fit needs "
          "at least 2, at distinct h)\n"
          "* singular Gram matrix\n");
  }
  SECTION("no rows") {
    CHECK(rkhs::format_convergence_table("l2_error", "g", "n", {}, std::nullopt) ==
          "l2_error, group g\n"
          "n  l2_error  rate\n"
          "fitted rate: not available (no points)\n");
  }
}

TEST_CASE("the pairwise column follows the footer's model: callers explain a missing fit",
          "[rates]") {
  Series s;
  for (double n : {4.0, 8.0, 12.0}) s.add(n, std::exp(-0.3 * n));
  const auto fit = rkhs::fit_exponential(s.x, s.y);
  CHECK(rkhs::format_convergence_table("l2_error", "gaussian", "n", s.rows, fit, "flagged",
                                       rkhs::RateModel::exponential) ==
        "l2_error, group gaussian\n"
        " n   l2_error    rate\n"
        " 4  3.012e-01       -\n"
        " 8  9.072e-02  -0.300\n"
        "12  2.732e-02  -0.300\n"
        "fitted rate (exponential in n): -0.300 ± 0.000 (95% CI [-0.300, -0.300], R² = 1.000, "
        "3 points)\n");

  // Every value flagged: the rows have positive values, but none was usable for the fit.
  Series flagged;
  flagged.add(10, 4.2e-8, true);
  flagged.add(20, 6.7e-8, true);
  const auto table = rkhs::format_convergence_table(
      "power_function_sup", "g", "n", flagged.rows, std::nullopt, "at the floor",
      rkhs::RateModel::power_law, "0 of 2 points usable after excluding 2 failed or flagged");
  CHECK(table.find("fitted rate: not available (0 of 2 points usable after excluding 2 failed or "
                   "flagged)\n") != std::string::npos);
}
