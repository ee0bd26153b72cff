#include "rkhs/adaptive/averaged_limit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "rkhs/core/cancellation.hpp"

namespace rkhs {

GaussLegendreRule gauss_legendre(std::size_t q) {
  if (q == 0) throw std::invalid_argument("a Gauss-Legendre rule needs at least one node");
  GaussLegendreRule rule;
  rule.nodes.assign(q, 0.0);
  rule.weights.assign(q, 0.0);
  const double order = static_cast<double>(q);
  // P_q(x) and P_q'(x) by the recurrence k P_k = (2k - 1) x P_{k-1} - (k - 1) P_{k-2}.
  auto legendre = [&](double x, double& derivative) {
    double previous = 1.0, current = x;
    for (std::size_t k = 2; k <= q; ++k) {
      const double kd = static_cast<double>(k);
      const double next = ((2 * kd - 1) * x * current - (kd - 1) * previous) / kd;
      previous = current;
      current = next;
    }
    derivative = order * (x * current - previous) / (x * x - 1);
    return current;
  };
  constexpr double eps = std::numeric_limits<double>::epsilon();
  for (std::size_t i = 0; i < q / 2; ++i) {
    // The i-th largest root, from Tricomi's first-order estimate.
    double x = std::cos(std::numbers::pi * (static_cast<double>(i) + 0.75) / (order + 0.5));
    double derivative = 0;
    for (int iteration = 0, converged = 0; iteration < 100 && converged < 2; ++iteration) {
      const double step = legendre(x, derivative) / derivative;
      x -= step;
      if (std::abs(step) <= 4 * eps) ++converged;  // one more step after convergence
    }
    legendre(x, derivative);
    const double weight = 2 / ((1 - x * x) * derivative * derivative);
    rule.nodes[q - 1 - i] = x;
    rule.nodes[i] = -x;
    rule.weights[q - 1 - i] = weight;
    rule.weights[i] = weight;
  }
  if (q % 2 == 1) {  // the middle node is 0; P_q'(0) from the recurrence at x = 0
    double derivative = 0;
    legendre(0.0, derivative);
    rule.weights[q / 2] = 2 / (derivative * derivative);
  }
  return rule;
}

namespace {

// The spectrum a pseudo-inverse solve divides by: from its smallest kept eigenvalue to the
// largest.
GramSpectrum kept_spectrum(double lambda_max, double smallest_kept) {
  GramSpectrum out;
  out.lambda_min = smallest_kept;
  out.lambda_max = lambda_max;
  out.condition_number = lambda_max / smallest_kept;
  return out;
}

// Mbar, bbar and mean(f^2) under one composite rule.
struct Moments {
  Eigen::MatrixXd gram;
  Eigen::VectorXd load;
  double mean_square = 0;
  std::size_t nodes = 0;
  std::size_t panels = 0;
};

// The pieces [breakpoints[k], breakpoints[k + 1]] with panels_per_piece[k] << refinement equal
// panels each, q Gauss-Legendre nodes per panel. Dense: nodes are processed in blocks, phi at a
// block's nodes, scaled by sqrt(w), updates Mbar by one rank-`block` product. Sparse (features,
// of which few are nonzero at a point): each node adds w phi_i phi_j for its nonzero pairs only,
// O(nonzeros^2) instead of O(n^2).
Moments integrate(KernelBasis& basis, Eigen::Index n, const std::function<double(double)>& road,
                  const std::vector<double>& breakpoints,
                  const std::vector<std::size_t>& panels_per_piece, std::size_t refinement,
                  const GaussLegendreRule& rule, double length, bool sparse = false) {
  constexpr Eigen::Index block_size = 512;
  Moments out;
  out.gram = Eigen::MatrixXd::Zero(n, n);
  out.load = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd block(n, sparse ? 1 : block_size);  // column c: sqrt(w_c) phi(s_c)
  Eigen::VectorXd scaled_road(block_size);
  std::vector<Eigen::Index> nonzero;
  Eigen::Index filled = 0;
  auto flush = [&] {
    if (filled == 0) return;
    if (sparse) {
      const auto column = block.col(0);
      nonzero.clear();
      for (Eigen::Index i = 0; i < n; ++i)
        if (column(i) != 0.0) nonzero.push_back(i);
      for (std::size_t a = 0; a < nonzero.size(); ++a) {
        const Eigen::Index i = nonzero[a];
        out.load(i) += column(i) * scaled_road(0);
        for (std::size_t b = 0; b < nonzero.size(); ++b) {
          const Eigen::Index j = nonzero[b];
          if (j <= i) out.gram(i, j) += column(i) * column(j);
        }
      }
      filled = 0;
      return;
    }
    out.gram.selfadjointView<Eigen::Lower>().rankUpdate(block.leftCols(filled));
    out.load.noalias() += block.leftCols(filled) * scaled_road.head(filled);
    filled = 0;
  };
  const std::size_t q = rule.nodes.size();
  for (std::size_t k = 0; k + 1 < breakpoints.size(); ++k) {
    const std::size_t panels = panels_per_piece[k] << refinement;
    const double begin = breakpoints[k], piece = breakpoints[k + 1] - begin;
    for (std::size_t p = 0; p < panels; ++p) {
      const double a = begin + piece * static_cast<double>(p) / static_cast<double>(panels);
      const double b = begin + piece * static_cast<double>(p + 1) / static_cast<double>(panels);
      const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
      for (std::size_t j = 0; j < q; ++j) {
        const double s = mid + half * rule.nodes[j], w = half * rule.weights[j];
        const double f = road(s);
        const double root_w = std::sqrt(w);
        basis.evaluate(s, block.col(filled).data());
        block.col(filled) *= root_w;
        scaled_road(filled) = root_w * f;
        out.mean_square += w * f * f;
        if (++filled == block.cols()) flush();
      }
    }
    out.panels += panels;
    check_cancelled();
  }
  flush();
  out.gram.triangularView<Eigen::StrictlyUpper>() = out.gram.transpose();
  out.gram /= length;
  out.load /= length;
  out.mean_square /= length;
  out.nodes = out.panels * q;
  return out;
}

// The change from `coarse` to `fine` relative to the Cauchy-Schwarz scales of the entries:
// |Mbar_ij| <= max_i Mbar_ii and |bbar_i| <= max_i sqrt(Mbar_ii) rms(f).
double relative_change(const Moments& coarse, const Moments& fine) {
  const double gram_scale = fine.gram.diagonal().maxCoeff();
  const double load_scale = std::sqrt(gram_scale * fine.mean_square);
  const double gram_change = (fine.gram - coarse.gram).cwiseAbs().maxCoeff();
  const double load_change = (fine.load - coarse.load).cwiseAbs().maxCoeff();
  auto relative = [](double change, double scale) {
    if (change == 0) return 0.0;
    return scale > 0 ? change / scale : std::numeric_limits<double>::infinity();
  };
  return std::max(relative(gram_change, gram_scale), relative(load_change, load_scale));
}

}  // namespace

namespace {

// The composite rule's pieces: the breakpoints (the ends, the kernel's kinks, the centres of a
// non-analytic stationary kernel and the road's kinks, sorted; points closer than 1e-13 L are
// one: moving a kink by that much changes an integral by O((1e-13 L)^2)) and the initial panels
// of each piece.
// The length of the averaging range: the domain's, or the path's part of it.
double range_length(const AnyKernel& kernel, const AveragedLimitQuadrature& quadrature) {
  return quadrature.range_length > 0 ? quadrature.range_length : kernel.domain().length;
}

struct Pieces {
  std::vector<double> breakpoints;
  std::vector<std::size_t> panels_per_piece;
  std::size_t initial_panels = 0;
};

Pieces quadrature_pieces(const AnyKernel& kernel, std::span<const double> centres,
                         std::span<const double> road_kinks,
                         const AveragedLimitQuadrature& quadrature) {
  if (quadrature.nodes_per_panel == 0 || quadrature.initial_panels == 0 ||
      !(quadrature.tolerance > 0))
    throw std::invalid_argument(
        "the averaged limit's quadrature needs nodes_per_panel >= 1, initial_panels >= 1 and a "
        "positive tolerance");
  const Domain& domain = kernel.domain();
  const double begin = quadrature.range_from;
  const double end = begin + range_length(kernel, quadrature);
  const double length = end - begin;
  std::vector<double> breakpoints{begin, end};
  auto add = [&](double s) {
    if (domain.periodic) s = domain.wrap(s);
    if (s > begin && s < end) breakpoints.push_back(s);
  };
  for (double s : kernel.kink_points()) add(s);
  // A stationary kernel k0(x - y) that is not analytic is not smooth at 0 (Wendland, Matern),
  // and one with compact support not at its support radius: its sections are not smooth at
  // their centres and at c_i +- radius, which kink_points() (the integrator's restarts) leaves
  // out.
  const KernelProperties& properties = kernel.properties();
  if (properties.stationary && !properties.analytic)
    for (double c : centres) add(c);
  if (properties.stationary && properties.support_radius > 0)
    for (double c : centres) {
      add(c - properties.support_radius);
      add(c + properties.support_radius);
    }
  for (double s : road_kinks) add(s);
  std::sort(breakpoints.begin(), breakpoints.end());
  Pieces out;
  for (double s : breakpoints)
    if (out.breakpoints.empty() || s - out.breakpoints.back() > 1e-13 * length)
      out.breakpoints.push_back(s);
  out.breakpoints.back() = end;
  if (out.breakpoints.size() < 2) out.breakpoints = {begin, end};

  const double longest_panel = length / static_cast<double>(quadrature.initial_panels);
  out.panels_per_piece.resize(out.breakpoints.size() - 1);
  for (std::size_t k = 0; k + 1 < out.breakpoints.size(); ++k) {
    out.panels_per_piece[k] = static_cast<std::size_t>(std::max(
        1.0,
        std::ceil((out.breakpoints[k + 1] - out.breakpoints[k]) / longest_panel * (1 - 1e-12))));
    out.initial_panels += out.panels_per_piece[k];
  }
  return out;
}

// Mbar and bbar under the composite rule, its panels doubled until they change by at most the
// tolerance (or the node budget stops it): the accepted moments and how they were reached.
struct ConvergedMoments {
  Moments moments;
  std::size_t refinements = 0;
  double change = std::numeric_limits<double>::infinity();
  bool converged = false;
};

ConvergedMoments converged_moments(KernelBasis& basis, Eigen::Index n,
                                   const std::function<double(double)>& road, const Pieces& pieces,
                                   double length, const AveragedLimitQuadrature& quadrature,
                                   bool sparse) {
  const auto rule = gauss_legendre(quadrature.nodes_per_panel);
  const std::size_t q = quadrature.nodes_per_panel;
  auto at = [&](std::size_t refinement) {
    return integrate(basis, n, road, pieces.breakpoints, pieces.panels_per_piece, refinement, rule,
                     length, sparse);
  };
  ConvergedMoments out;
  Moments previous = at(0);
  Moments current;
  while (true) {
    if ((pieces.initial_panels << (out.refinements + 1)) * q > quadrature.max_nodes) break;
    ++out.refinements;
    current = at(out.refinements);
    out.change = relative_change(previous, current);
    if (out.change <= quadrature.tolerance && out.refinements >= quadrature.min_refinements) {
      out.converged = true;
      break;
    }
    previous = std::move(current);
    current = Moments{};
  }
  // Stopped by max_nodes: the finest rule tried.
  out.moments = out.converged ? std::move(current) : std::move(previous);
  return out;
}

// The accepted moments and their quadrature's record into `out`.
void record_moments(ConvergedMoments&& moments, AveragedLimit& out) {
  out.averaged_gram = std::move(moments.moments.gram);
  out.averaged_load = std::move(moments.moments.load);
  out.quadrature_nodes = moments.moments.nodes;
  out.panels = moments.moments.panels;
  out.refinements = moments.refinements;
  out.quadrature_change = moments.change;
  out.quadrature_converged = moments.converged;
}

}  // namespace

AveragedLimit averaged_limit(const AnyKernel& kernel, std::span<const double> centres,
                             const std::function<double(double)>& road,
                             std::span<const double> road_kinks, const SolverOptions& solver,
                             const AveragedLimitQuadrature& quadrature) {
  if (centres.empty()) throw std::invalid_argument("the averaged limit needs at least one centre");
  const Pieces pieces = quadrature_pieces(kernel, centres, road_kinks, quadrature);
  const auto n = static_cast<Eigen::Index>(centres.size());
  const auto basis = kernel.basis(centres);
  ConvergedMoments moments = converged_moments(
      *basis, n, road, pieces, range_length(kernel, quadrature), quadrature, /*sparse=*/false);
  const Moments& current = moments.moments;

  AveragedLimit out;
  const GramSolver gram_solver(current.gram, solver);
  out.coefficients = gram_solver.solve(current.load);
  out.solve_method = gram_solver.method();
  out.spectrum = gram_solver.spectrum();
  out.solved_spectrum = out.spectrum;
  if (const auto* kept = gram_solver.kept_values(); kept && kept->size() > 0)
    out.solved_spectrum = kept_spectrum(out.spectrum.lambda_max, kept->minCoeff());
  record_moments(std::move(moments), out);
  return out;
}

AveragedLimit averaged_limit_in_features(const AnyKernel& kernel,
                                         const std::function<double(double)>& road,
                                         std::span<const double> road_kinks,
                                         const AveragedLimitQuadrature& quadrature) {
  const auto basis = kernel.feature_basis();
  if (!basis)
    throw std::invalid_argument(fmt::format(
        "the averaged limit in feature coordinates needs a kernel with a finite feature map; "
        "kernel '{}' has none",
        kernel.name()));
  const Pieces pieces = quadrature_pieces(kernel, {}, road_kinks, quadrature);
  const auto count = static_cast<Eigen::Index>(basis->size());
  ConvergedMoments moments = converged_moments(
      *basis, count, road, pieces, range_length(kernel, quadrature), quadrature, /*sparse=*/true);
  const Moments& current = moments.moments;

  // E is singular by design (the features are redundant): beta = E^+ bbar over the eigenvalues
  // above F eps lambda_max, the minimum-norm solution, in the range of E.
  AveragedLimit out;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(current.gram);
  if (eigen.info() != Eigen::Success)
    throw std::runtime_error(
        "symmetric eigen-decomposition of the averaged feature Gram matrix did not converge");
  const Eigen::VectorXd& values = eigen.eigenvalues();  // increasing
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double cutoff = static_cast<double>(count) * eps * values(count - 1);
  Eigen::Index first = 0;
  while (first < count && !(values(first) > cutoff)) ++first;
  const Eigen::Index rank = count - first;
  const auto kept = eigen.eigenvectors().rightCols(rank);
  Eigen::VectorXd projected = kept.transpose() * current.load;
  projected.array() /= values.tail(rank).array();
  out.coefficients = kept * projected;
  out.solve_method = fmt::format("pseudo-inverse (rank {} of {}, cutoff {:.3e} lambda_max)", rank,
                                 count, static_cast<double>(count) * eps);
  out.spectrum.lambda_min = values(0);
  out.spectrum.lambda_max = values(count - 1);
  out.spectrum.singular = rank < count;
  out.spectrum.condition_number = out.spectrum.singular ? std::numeric_limits<double>::infinity()
                                                        : values(count - 1) / values(0);
  out.solved_spectrum = rank > 0 ? kept_spectrum(values(count - 1), values(first)) : out.spectrum;
  out.averaged_gram_eigenvalues = values;
  record_moments(std::move(moments), out);
  return out;
}

}  // namespace rkhs
