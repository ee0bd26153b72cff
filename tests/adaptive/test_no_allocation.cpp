// The right-hand side and the Jacobian of the coupled system allocate nothing: every global
// operator new of this test binary is counted while the hot calls run.
#include <atomic>
#include <catch2/catch.hpp>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <numbers>

#include "rkhs/adaptive/adaptive.hpp"
#include "rkhs/adaptive/lyapunov.hpp"
#include "rkhs/adaptive/plant.hpp"
#include "rkhs/approx/gram_solver.hpp"

namespace {
std::atomic<long> allocations{0};
thread_local bool counting = false;
}  // namespace

// Replacements of the global allocation functions for this executable (the standard allows
// exactly one definition per program): they count while `counting` is set. Every variant is
// replaced (plain, array, nothrow, aligned, sized), each pair on std::malloc / std::free or
// std::aligned_alloc / std::free, so that whatever form a library allocates with, the matching
// release is ours too: under AddressSanitizer, which also interposes these functions, a pair
// split between its versions and ours would be reported as alloc-dealloc-mismatch.
namespace {
void* counted_allocation(std::size_t size, std::size_t alignment) noexcept {
  if (counting) ++allocations;
  if (size == 0) size = 1;
  if (alignment <= alignof(std::max_align_t)) return std::malloc(size);
  // aligned_alloc wants a size that is a multiple of the alignment.
  return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void* counted_or_throw(std::size_t size, std::size_t alignment) {
  if (void* p = counted_allocation(size, alignment)) return p;
  throw std::bad_alloc();
}
constexpr std::size_t plain = alignof(std::max_align_t);
std::size_t value(std::align_val_t alignment) {
  return static_cast<std::size_t>(alignment);
}
}  // namespace

void* operator new(std::size_t size) {
  return counted_or_throw(size, plain);
}
void* operator new[](std::size_t size) {
  return counted_or_throw(size, plain);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return counted_allocation(size, plain);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return counted_allocation(size, plain);
}
void* operator new(std::size_t size, std::align_val_t a) {
  return counted_or_throw(size, value(a));
}
void* operator new[](std::size_t size, std::align_val_t a) {
  return counted_or_throw(size, value(a));
}
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_allocation(size, value(a));
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return counted_allocation(size, value(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}

using namespace rkhs;

TEST_CASE("no heap allocation in the right-hand side or the Jacobian", "[adaptive]") {
  const Domain track{2 * std::numbers::pi * 4, true};
  const auto* plant_entry = plant_registry().find("quarter_car");
  const auto plant = plant_entry->factory(ParameterSet::resolve(plant_entry->info.parameters, {}));
  const auto P = solve_lyapunov(plant->A(), Eigen::MatrixXd::Identity(4, 4)).P;
  const std::function<double(double)> road = [](double s) { return 2 * std::sin(s / 4); };
  const std::function<double(double)> slope = [](double s) { return 0.5 * std::cos(s / 4); };
  for (const std::string name : {"gaussian", "bspline", "wendland", "matern"}) {
    const auto* entry = kernel_registry().find(name);
    const auto kernel = entry->factory(ParameterSet::resolve(entry->info.parameters, {}), track);
    std::vector<double> centres;
    for (int i = 0; i < 40; ++i) centres.push_back(track.length * i / 40.0);
    const GramSolver solver(kernel->gram(centres), {});
    // The gradient law (a scalar map), the rkhs law (dense), and a low-rank map (the form of a
    // pseudo-inverse of low rank: here G's 10 largest eigenpairs).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(kernel->gram(centres));
    const auto low_rank = LearningMap::low_rank(eigen.eigenvectors().rightCols(10),
                                                eigen.eigenvalues().tail(10).cwiseInverse());
    const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(40, 40);
    for (const std::string law : {"gradient", "rkhs", "low_rank"}) {
      const auto map = law == "gradient" ? LearningMap::dense(identity)
                       : law == "rkhs"   ? LearningMap::dense(solver.solve(identity))
                                         : low_rank;
      const auto basis = kernel->basis(centres);
      AdaptiveSystem system(plant->A(), plant->B(), P, *basis, map, road, slope, track, 0.3);
      const auto m = system.dimension();
      Eigen::VectorXd z = Eigen::VectorXd::Constant(m, 0.1), dz(m), dfdt(m);
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
      system.rhs(z.data(), dz.data(), 1.0);  // first calls may size scratch buffers
      system.jacobian(z.data(), J.data(), 1.0, dfdt.data());
      allocations = 0;
      counting = true;
      for (int k = 0; k < 50; ++k) {
        system.rhs(z.data(), dz.data(), 1.0 + 1.7 * k);
        system.jacobian(z.data(), J.data(), 1.0 + 1.7 * k, dfdt.data());
      }
      counting = false;
      INFO(name << " " << law);
      CHECK(allocations == 0);
    }
  }
  // rkhs_embedding: the feature coordinates of the B-spline kernel (F = 508 features at the
  // defaults), the scalar map Gamma^-1 applied to phi(s) (as measure_adaptive does), and the
  // feature basis's own mapped evaluation.
  {
    const auto* entry = kernel_registry().find("bspline");
    const auto kernel = entry->factory(ParameterSet::resolve(entry->info.parameters, {}), track);
    for (const auto signal :
         {AdaptiveSystem::LearningSignal::from_phi, AdaptiveSystem::LearningSignal::by_basis}) {
      const auto basis = kernel->feature_basis();
      REQUIRE(basis);
      const auto count = static_cast<Eigen::Index>(basis->size());
      AdaptiveSystem system(plant->A(), plant->B(), P, *basis, LearningMap::scalar(count, 1e3),
                            road, slope, track, 0.3, signal);
      const auto m = system.dimension();
      Eigen::VectorXd z = Eigen::VectorXd::Constant(m, 0.1), dz(m), dfdt(m);
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> J(m, m);
      system.rhs(z.data(), dz.data(), 1.0);
      system.jacobian(z.data(), J.data(), 1.0, dfdt.data());
      allocations = 0;
      counting = true;
      for (int k = 0; k < 50; ++k) {
        system.rhs(z.data(), dz.data(), 1.0 + 1.7 * k);
        system.jacobian(z.data(), J.data(), 1.0 + 1.7 * k, dfdt.data());
      }
      counting = false;
      INFO("rkhs_embedding, signal " << static_cast<int>(signal));
      CHECK(allocations == 0);
    }
  }
  // The counter works: an allocation while counting is seen.
  allocations = 0;
  counting = true;
  auto* probe = new std::vector<double>(16);
  counting = false;
  delete probe;
  CHECK(allocations >= 1);
}
