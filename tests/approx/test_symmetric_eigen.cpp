// symmetric_eigen is Eigen's SelfAdjointEigenSolver bit for bit (its eigenvalues, and its
// eigenvectors when asked for), and it stops at a cancellation point part-way.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <string>

#include "rkhs/approx/symmetric_eigen.hpp"
#include "rkhs/core/cancellation.hpp"

using namespace rkhs;

namespace {

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

Eigen::MatrixXd random_spd(Eigen::Index n, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i < n; ++i) a(i, j) = normal(random);
  Eigen::MatrixXd spd = a * a.transpose();
  spd.diagonal().array() += 1e-3;
  return spd;
}

// exp(-(x_i - x_j)^2 / (2 sigma^2)) on n points spread over [-4, 4]: singular to working
// precision once the spacing is well below sigma.
Eigen::MatrixXd gaussian_gram(Eigen::Index n, double sigma) {
  Eigen::MatrixXd g(n, n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i < n; ++i) {
      const double step = n > 1 ? 8.0 / static_cast<double>(n - 1) : 0.0;
      const double d = static_cast<double>(i - j) * step;
      g(i, j) = std::exp(-d * d / (2 * sigma * sigma));
    }
  return g;
}

void check_identical(const Eigen::MatrixXd& matrix, const std::string& what) {
  INFO(what << ", n = " << matrix.rows());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> values_only(matrix, Eigen::EigenvaluesOnly);
  const SymmetricEigen ours_values = symmetric_eigen(matrix, false);
  REQUIRE(values_only.info() == Eigen::Success);
  CHECK(ours_values.info == Eigen::Success);
  CHECK(same_bits(ours_values.values, values_only.eigenvalues()));
  CHECK(ours_values.vectors.size() == 0);

  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> pairs(matrix, Eigen::ComputeEigenvectors);
  const SymmetricEigen ours_pairs = symmetric_eigen(matrix, true);
  REQUIRE(pairs.info() == Eigen::Success);
  CHECK(ours_pairs.info == Eigen::Success);
  CHECK(same_bits(ours_pairs.values, pairs.eigenvalues()));
  CHECK(same_bits(ours_pairs.vectors, pairs.eigenvectors()));
}

}  // namespace

TEST_CASE("symmetric_eigen is SelfAdjointEigenSolver bit for bit", "[symmetric_eigen]") {
  for (const Eigen::Index n : {1, 2, 3, 4, 17, 64, 300}) {
    check_identical(random_spd(n, 7 + static_cast<unsigned>(n)), "random SPD");
    check_identical(gaussian_gram(n, 1.0), "Gaussian Gram, sigma = 1");
  }
  for (const Eigen::Index n : {2, 50, 300, 600})
    check_identical(gaussian_gram(n, 2.0), "singular Gaussian Gram, sigma = 2");
  // Indefinite, zero, scaled far from 1 (the solver's scaling by the largest entry), repeated
  // eigenvalues, a diagonal (already tridiagonal) and only the lower triangle read.
  Eigen::MatrixXd indefinite = random_spd(40, 3);
  indefinite.diagonal().array() -= 20.0;
  check_identical(indefinite, "indefinite");
  check_identical(Eigen::MatrixXd::Zero(5, 5), "zero");
  check_identical(1e-300 * random_spd(30, 4), "tiny");
  check_identical(1e300 * gaussian_gram(30, 1.0), "huge");
  check_identical(Eigen::MatrixXd::Identity(20, 20), "identity");
  Eigen::MatrixXd diagonal = Eigen::MatrixXd::Zero(12, 12);
  for (int i = 0; i < 12; ++i) diagonal(i, i) = (i * 7) % 5;
  check_identical(diagonal, "diagonal with repeated values");
  Eigen::MatrixXd lower = random_spd(25, 5);
  lower.triangularView<Eigen::StrictlyUpper>().setConstant(1e9);
  check_identical(lower, "upper triangle ignored");
}

TEST_CASE("symmetric_eigen stops at a cancellation point part-way", "[symmetric_eigen]") {
  const Eigen::MatrixXd gram = gaussian_gram(200, 1.0);
  for (const bool vectors : {false, true}) {
    // Count the checks of a whole decomposition: at least one per Householder step (n - 1), and
    // with the vectors one per reflector accumulated (n - 1 more).
    long checks = 0;
    const std::function<bool()> count = [&] { return ++checks < 0; };
    {
      const CancellationScope scope(count, std::nullopt);
      symmetric_eigen(gram, vectors);
    }
    CHECK(checks >= (vectors ? 2 * 199 : 199));
    // A stop requested half-way through them ends the decomposition there.
    long seen = 0;
    const long stop_at = checks / 2;
    const std::function<bool()> stop = [&] { return ++seen >= stop_at; };
    const CancellationScope scope(stop, std::nullopt);
    CHECK_THROWS_AS(symmetric_eigen(gram, vectors), TrialCancelled);
    CHECK(seen == stop_at);
  }
  // A passed deadline: TrialTimeLimitExceeded at the first check.
  const CancellationScope late({}, std::chrono::steady_clock::now() - std::chrono::seconds(1));
  CHECK_THROWS_AS(symmetric_eigen(gram, true), TrialTimeLimitExceeded);
}
