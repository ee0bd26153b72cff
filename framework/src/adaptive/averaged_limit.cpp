#include "rkhs/adaptive/averaged_limit.hpp"

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

// Mbar, bbar and mean(f^2) under one composite rule.
struct Moments {
  Eigen::MatrixXd gram;
  Eigen::VectorXd load;
  double mean_square = 0;
  std::size_t nodes = 0;
  std::size_t panels = 0;
};

// The pieces [breakpoints[k], breakpoints[k + 1]] with panels_per_piece[k] << refinement equal
// panels each, q Gauss-Legendre nodes per panel. Nodes are processed in blocks: phi at a block's
// nodes, scaled by sqrt(w), updates Mbar by one rank-`block` product.
Moments integrate(KernelBasis& basis, Eigen::Index n, const std::function<double(double)>& road,
                  const std::vector<double>& breakpoints,
                  const std::vector<std::size_t>& panels_per_piece, std::size_t refinement,
                  const GaussLegendreRule& rule, double length) {
  constexpr Eigen::Index block_size = 512;
  Moments out;
  out.gram = Eigen::MatrixXd::Zero(n, n);
  out.load = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd block(n, block_size);  // column c: sqrt(w_c) phi(s_c)
  Eigen::VectorXd scaled_road(block_size);
  Eigen::Index filled = 0;
  auto flush = [&] {
    if (filled == 0) return;
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
        if (++filled == block_size) flush();
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

AveragedLimit averaged_limit(const AnyKernel& kernel, std::span<const double> centres,
                             const std::function<double(double)>& road,
                             std::span<const double> road_kinks, const SolverOptions& solver,
                             const AveragedLimitQuadrature& quadrature) {
  if (centres.empty()) throw std::invalid_argument("the averaged limit needs at least one centre");
  if (quadrature.nodes_per_panel == 0 || quadrature.initial_panels == 0 ||
      !(quadrature.tolerance > 0))
    throw std::invalid_argument(
        "the averaged limit's quadrature needs nodes_per_panel >= 1, initial_panels >= 1 and a "
        "positive tolerance");
  const Domain& domain = kernel.domain();
  const double length = domain.length;

  // Breakpoints: the ends, the kernel's kinks, the centres of a non-analytic stationary kernel
  // and the road's kinks, sorted; points closer than
  // 1e-13 L are one (moving a kink by that much changes an integral by O((1e-13 L)^2)).
  std::vector<double> breakpoints{0.0, length};
  auto add = [&](double s) {
    if (domain.periodic) s = domain.wrap(s);
    if (s > 0 && s < length) breakpoints.push_back(s);
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
  std::vector<double> merged;
  for (double s : breakpoints)
    if (merged.empty() || s - merged.back() > 1e-13 * length) merged.push_back(s);
  merged.back() = length;
  if (merged.size() < 2) merged = {0.0, length};

  const double longest_panel = length / static_cast<double>(quadrature.initial_panels);
  std::vector<std::size_t> panels_per_piece(merged.size() - 1);
  std::size_t initial_panels = 0;
  for (std::size_t k = 0; k + 1 < merged.size(); ++k) {
    panels_per_piece[k] = static_cast<std::size_t>(
        std::max(1.0, std::ceil((merged[k + 1] - merged[k]) / longest_panel * (1 - 1e-12))));
    initial_panels += panels_per_piece[k];
  }

  const auto n = static_cast<Eigen::Index>(centres.size());
  const auto basis = kernel.basis(centres);
  const auto rule = gauss_legendre(quadrature.nodes_per_panel);
  const std::size_t q = quadrature.nodes_per_panel;

  Moments previous = integrate(*basis, n, road, merged, panels_per_piece, 0, rule, length);
  Moments current;
  std::size_t refinement = 0;
  double change = std::numeric_limits<double>::infinity();
  bool converged = false;
  while (true) {
    if ((initial_panels << (refinement + 1)) * q > quadrature.max_nodes) break;
    ++refinement;
    current = integrate(*basis, n, road, merged, panels_per_piece, refinement, rule, length);
    change = relative_change(previous, current);
    if (change <= quadrature.tolerance && refinement >= quadrature.min_refinements) {
      converged = true;
      break;
    }
    previous = std::move(current);
    current = Moments{};
  }
  if (!converged) current = std::move(previous);  // stopped by max_nodes: the finest rule tried

  AveragedLimit out;
  const GramSolver gram_solver(current.gram, solver);
  out.coefficients = gram_solver.solve(current.load);
  out.solve_method = gram_solver.method();
  out.spectrum = gram_solver.spectrum();
  out.averaged_gram = std::move(current.gram);
  out.averaged_load = std::move(current.load);
  out.quadrature_nodes = current.nodes;
  out.panels = current.panels;
  out.refinements = refinement;
  out.quadrature_change = change;
  out.quadrature_converged = converged;
  return out;
}

}  // namespace rkhs
