// Built-in projections (docs/projections.md): kernel interpolation at the centres, and three
// projections onto the spline spaces V_j of the multiscale B-spline kernel (the span of levels
// 0..j, which is the span of the level-j B-splines since the levels are nested):
//   mra_level          the H-orthogonal projection onto V_j;
//   l2_projection      the L2(Omega)-orthogonal projection onto V_j;
//   quasi_interpolant  a local quasi-interpolant onto V_j: spline k's coefficient is the B_k
//                      coefficient of the polynomial interpolating f at p + 1 points of one cell
//                      of its support. A projection onto V_j (it reproduces V_j: on a cell a
//                      spline is a polynomial, and the active B-splines there are linearly
//                      independent), bounded in L-infinity independently of j, neither
//                      H-orthogonal nor nested.
// They are written in projection.hpp's form: the basis b_i = B_{j,i} is a combination of the
// kernel sections at the finest level's support centres Z (which span the kernel's space V_J,
// so this is exact): E = K_ZZ^-1 B_j(Z).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "rkhs/approx/projection.hpp"
#include "rkhs/kernels/bspline.hpp"

namespace rkhs {
namespace {

using kernels::MultiscaleBSpline;

/// Kernel interpolation at the centres (the study's solver decides: Cholesky, a pseudo-inverse
/// when G is singular, or a regularised solve): S = Y = the centres.
class Interpolation final : public Projection {
 public:
  static PluginInfo info() {
    return {"interpolation",
            "kernel interpolation at the n centres: the H-orthogonal projection onto "
            "span{k(c_i, .)}",
            {},
            {}};
  }
  explicit Interpolation(const ParameterSet&) {}
  void check(const AnyKernel&, std::size_t) const override {}
  ProjectionProperties properties() const override {
    return {ProjectionResolution::centres, true, true, 1.0, {}};
  }
  void build(const ProjectionRequest& request, ProjectionOperator& out) const override {
    const std::size_t d = static_cast<std::size_t>(request.kernel.domain().dimension);
    const auto n = request.centres.size() / d;
    if (n == 0) throw std::invalid_argument("projection 'interpolation' needs centres");
    const Eigen::MatrixXd gram = request.kernel.gram(request.centres);
    interpolation_operator(request.kernel, request.centres, gram,
                           GramSolver(gram, request.solver), out);
  }
};

/// The level-j B-splines B_{j,k}(u) = N_p(u / h_j - k) of the kernel of a request, h_j = L / n_j,
/// n_j = n0 2^j, evaluated as the kernel evaluates its features (wrapped on a periodic domain,
/// clamped to [0, L] on an interval; the cell of a point is the floor of u / h_j).
class SplineLevel {
 public:
  SplineLevel(const ProjectionRequest& request, std::string_view projection) {
    const AnyKernel& kernel = request.kernel;
    if (kernel.domain().dimension != 1)
      throw std::invalid_argument(fmt::format(
          "projection '{}' is defined on tracks and intervals (d = 1); this domain has d = {}",
          projection, kernel.domain().dimension));
    const ParameterSet& p = kernel.parameters();
    degree_ = static_cast<int>(p.integer("degree"));
    const auto n0 = p.integer("n0");
    finest_ = static_cast<int>(p.integer("J"));
    length_ = kernel.domain().length;
    periodic_ = kernel.domain().periodic;
    const auto n = static_cast<long long>(request.n);
    level_ = -1;
    for (int j = 0; j <= MultiscaleBSpline::max_level; ++j)
      if ((n0 << j) == n) level_ = j;
    if (level_ < 0)
      throw std::invalid_argument(fmt::format(
          "projection '{}' builds the splines of level j with n = n0 2^j cells: n = {} is not "
          "n0 = {} times a power of 2",
          projection, n, n0));
    if (level_ > finest_)
      throw std::invalid_argument(fmt::format(
          "projection '{}': n = {} asks for level j = {}, finer than the kernel's finest level "
          "J = {}",
          projection, n, level_, finest_));
    cells_ = static_cast<int>(n0 << level_);
    finest_cells_ = static_cast<int>(n0 << finest_);
  }

  int degree() const noexcept { return degree_; }
  int level() const noexcept { return level_; }
  int cells() const noexcept { return cells_; }
  double cell_width() const noexcept { return length_ / cells_; }
  bool periodic() const noexcept { return periodic_; }
  /// Number of level-j splines: n_j (periodic), n_j + p (interval: k = -p .. n_j - 1).
  Eigen::Index dimension() const noexcept { return cells_ + (periodic_ ? 0 : degree_); }
  /// The basis index of spline k (k wrapped modulo n_j when periodic, shifted by p otherwise).
  Eigen::Index index(int k) const noexcept {
    if (periodic_) return ((k % cells_) + cells_) % cells_;
    return k + degree_;
  }

  /// M(m, i) = B_i(points[m]).
  Eigen::MatrixXd values(std::span<const double> points) const {
    Eigen::MatrixXd out =
        Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(points.size()), dimension());
    for (std::size_t m = 0; m < points.size(); ++m) {
      const double x = position(points[m]);
      auto cell = static_cast<int>(std::floor(x));
      double t = x - cell;   // in [0, 1)
      if (cell >= cells_) {  // x = n_j: the seam (periodic) or u = L (the last cell's end)
        if (periodic_) {
          cell -= cells_;
        } else {
          cell = cells_ - 1;
          t = 1.0;
        }
      }
      for (int i = 0; i <= degree_; ++i)
        out(static_cast<Eigen::Index>(m), index(cell - i)) +=
            MultiscaleBSpline::cardinal_bspline(degree_, t + i);
    }
    return out;
  }

  /// Points Z, one per finest-level spline, where the kernel's sections span its whole space
  /// V_J: spline interpolation at Z is well posed and well conditioned. Periodic: the support
  /// centres (k + (p + 1) / 2) h_J (cardinal interpolation; knots for odd p, midpoints for even
  /// p). Interval: the Greville abscissae of V_J written with the clamped knots (0 and L of
  /// multiplicity p + 1), means of p consecutive knots, from 0 to L (cell midpoints for p = 0).
  /// Uniformly spaced points would drift across the knots and, for even p, sit on them
  /// somewhere, where quadratic interpolation is singular.
  std::vector<double> finest_support_centres() const {
    const int count = finest_cells_ + (periodic_ ? 0 : degree_);
    const double h = length_ / finest_cells_;
    std::vector<double> z(static_cast<std::size_t>(count));
    for (int k = 0; k < count; ++k) {
      double x;
      if (periodic_) {
        x = std::fmod((k + 0.5 * (degree_ + 1)) * h, length_);
      } else if (degree_ == 0) {
        x = (k + 0.5) * h;
      } else {
        // Clamped knots t_i = clamp(i - p, 0, n_J) h, i = 0 .. n_J + 2p; the Greville abscissa
        // of spline k is (t_{k+1} + ... + t_{k+p}) / p.
        double sum = 0;
        for (int i = k + 1; i <= k + degree_; ++i) sum += std::clamp(i - degree_, 0, finest_cells_);
        x = sum / degree_ * h;
      }
      z[static_cast<std::size_t>(k)] = x;
    }
    return z;
  }

  /// The knots of level j in [0, L) (periodic) or [0, L] (interval).
  std::vector<double> knots() const {
    std::vector<double> out;
    for (int k = 0; k < cells_ + (periodic_ ? 0 : 1); ++k) out.push_back(k * cell_width());
    return out;
  }

  /// Fills the basis part of `out` (Y = Z, E = K_ZZ^-1 B_j(Z)), its level and mesh; returns
  /// the H-Gram matrix of the basis, G_B = B_j(Z)^T E.
  Eigen::MatrixXd fill_basis(const ProjectionRequest& request, ProjectionOperator& out) const {
    const auto z = finest_support_centres();
    const GramSolver sections(request.kernel.gram(z), request.solver);
    const Eigen::MatrixXd at_z = values(z);
    std::copy(z.begin(), z.end(), out.basis_points().begin());
    out.basis_coefficients() = sections.solve(at_z);
    out.level = level_;
    out.set_mesh(knots());
    out.set_solve_method(fmt::format("sections at the finest level: {}", sections.method()));
    Eigen::MatrixXd gram = at_z.transpose() * out.basis_coefficients();
    return 0.5 * (gram + gram.transpose());
  }

  std::size_t basis_point_count() const noexcept {
    return static_cast<std::size_t>(finest_cells_ + (periodic_ ? 0 : degree_));
  }

 private:
  // u in level-j knot units, in [0, n_j] (wrapped or clamped).
  double position(double u) const noexcept {
    if (periodic_) {
      double w = std::fmod(u, length_);
      if (w < 0) w += length_;
      return w * cells_ / length_;
    }
    const double c = u < 0 ? 0.0 : (u > length_ ? length_ : u);
    return std::min(c * cells_ / length_, static_cast<double>(cells_));
  }

  int degree_ = 1, level_ = 0, finest_ = 0, cells_ = 1, finest_cells_ = 1;
  double length_ = 1;
  bool periodic_ = true;
};

PluginInfo level_info(const char* name, const char* doc) {
  return {name, doc, {}, {}};
}

/// The H-orthogonal projection onto V_j: G_B c = ((f, b_i)_H)_i with (f, b_i)_H =
/// sum_z E_zi f(z), so S = Z and W = G_B^-1 E^T.
class MraLevel final : public Projection {
 public:
  static PluginInfo info() {
    return level_info("mra_level",
                      "H-orthogonal projection onto V_j, the span of the B-spline kernel's "
                      "levels 0..j (n = n0 2^j)");
  }
  explicit MraLevel(const ParameterSet&) {}
  void check(const AnyKernel& kernel, std::size_t n) const override {
    SplineLevel(ProjectionRequest{kernel, n, {}, {}}, "mra_level");
  }
  ProjectionProperties properties() const override {
    return {ProjectionResolution::level, true, true, 1.0, "bspline"};
  }
  void build(const ProjectionRequest& request, ProjectionOperator& out) const override {
    const SplineLevel level(request, "mra_level");
    const auto points = level.basis_point_count();
    out.resize(static_cast<std::size_t>(level.dimension()), points, points);
    const Eigen::MatrixXd gram = level.fill_basis(request, out);
    std::copy(out.basis_points().begin(), out.basis_points().end(), out.samples().begin());
    const GramSolver basis(gram, request.solver);
    out.weights() = basis.solve(Eigen::MatrixXd(out.basis_coefficients().transpose()));
  }
};

/// The L2(Omega)-orthogonal projection onto V_j: M c = (int f b_i)_i, M the mass matrix, both
/// by Gauss-Legendre with p + 1 points on every finest-level cell (exact on the kernel's space,
/// whose functions are polynomials of degree p there).
class L2Projection final : public Projection {
 public:
  static PluginInfo info() {
    return level_info("l2_projection",
                      "L2(Omega)-orthogonal projection onto V_j, the span of the B-spline "
                      "kernel's levels 0..j (n = n0 2^j)");
  }
  explicit L2Projection(const ParameterSet&) {}
  void check(const AnyKernel& kernel, std::size_t n) const override {
    SplineLevel(ProjectionRequest{kernel, n, {}, {}}, "l2_projection");
  }
  ProjectionProperties properties() const override {
    return {ProjectionResolution::level, true, false, std::nullopt, "bspline"};
  }
  void build(const ProjectionRequest& request, ProjectionOperator& out) const override {
    const SplineLevel level(request, "l2_projection");
    const int p = level.degree();
    // Gauss-Legendre nodes and weights on [0, 1] for p + 1 = 1..4 points.
    static const std::array<std::vector<std::pair<double, double>>, 4> rules{{
        {{0.5, 1.0}},
        {{0.5 - 0.5 / std::sqrt(3.0), 0.5}, {0.5 + 0.5 / std::sqrt(3.0), 0.5}},
        {{0.5 - 0.5 * std::sqrt(0.6), 5.0 / 18},
         {0.5, 8.0 / 18},
         {0.5 + 0.5 * std::sqrt(0.6), 5.0 / 18}},
        {{0.5 - 0.5 * 0.8611363115940526, 0.5 * 0.3478548451374538},
         {0.5 - 0.5 * 0.3399810435848563, 0.5 * 0.6521451548625461},
         {0.5 + 0.5 * 0.3399810435848563, 0.5 * 0.6521451548625461},
         {0.5 + 0.5 * 0.8611363115940526, 0.5 * 0.3478548451374538}},
    }};
    const auto& rule = rules[static_cast<std::size_t>(p)];
    const auto& domain = request.kernel.domain();
    const auto finest = static_cast<int>(request.kernel.parameters().integer("n0")
                                         << request.kernel.parameters().integer("J"));
    const double width = domain.length / finest;
    std::vector<double> nodes;
    Eigen::VectorXd weights(static_cast<Eigen::Index>(finest) *
                            static_cast<Eigen::Index>(rule.size()));
    for (int c = 0; c < finest; ++c)
      for (const auto& [x, w] : rule) {
        weights[static_cast<Eigen::Index>(nodes.size())] = w * width;
        nodes.push_back((c + x) * width);
      }
    out.resize(static_cast<std::size_t>(level.dimension()), nodes.size(),
               level.basis_point_count());
    level.fill_basis(request, out);
    std::copy(nodes.begin(), nodes.end(), out.samples().begin());
    const Eigen::MatrixXd at_nodes = level.values(nodes);  // |S| x dim
    const Eigen::MatrixXd weighted = weights.asDiagonal() * at_nodes;
    Eigen::MatrixXd mass = at_nodes.transpose() * weighted;
    mass = 0.5 * (mass + mass.transpose());
    const Eigen::LLT<Eigen::MatrixXd> factor(mass);
    if (factor.info() != Eigen::Success)
      throw std::runtime_error(
          "projection 'l2_projection': the mass matrix is not positive "
          "definite");
    out.weights() = factor.solve(Eigen::MatrixXd(weighted.transpose()));
  }
};

/// The local quasi-interpolant: for spline k, the cell c of its support nearest the middle
/// (c = k + floor(p / 2), moved inside [0, n_j) on an interval), the p + 1 points
/// x_i = (c + (i + 1/2) / (p + 1)) h_j, and lambda_k f = the B_k coefficient of the polynomial
/// interpolating f there: a row of A^-1, A_il = N_p((i + 1/2) / (p + 1) + p - l), the same
/// matrix on every cell of uniform knots.
class QuasiInterpolant final : public Projection {
 public:
  static PluginInfo info() {
    return level_info("quasi_interpolant",
                      "local spline quasi-interpolant onto V_j (point values on one cell per "
                      "spline; reproduces V_j; bounded in L-infinity uniformly in j)");
  }
  explicit QuasiInterpolant(const ParameterSet&) {}
  void check(const AnyKernel& kernel, std::size_t n) const override {
    SplineLevel(ProjectionRequest{kernel, n, {}, {}}, "quasi_interpolant");
  }
  ProjectionProperties properties() const override {
    return {ProjectionResolution::level, false, false, std::nullopt, "bspline"};
  }
  void build(const ProjectionRequest& request, ProjectionOperator& out) const override {
    const SplineLevel level(request, "quasi_interpolant");
    const int p = level.degree();
    const int local = p + 1;
    Eigen::MatrixXd A(local, local);
    for (int i = 0; i < local; ++i)
      for (int l = 0; l < local; ++l)
        A(i, l) = MultiscaleBSpline::cardinal_bspline(p, (i + 0.5) / local + p - l);
    const Eigen::MatrixXd inverse = A.fullPivLu().inverse();
    const Eigen::Index dim = level.dimension();
    out.resize(static_cast<std::size_t>(dim), static_cast<std::size_t>(dim * local),
               level.basis_point_count());
    level.fill_basis(request, out);
    const int first = level.periodic() ? 0 : -p;
    for (int k = first; k < first + dim; ++k) {
      int cell = k + p / 2;
      if (!level.periodic()) cell = std::clamp(cell, 0, level.cells() - 1);
      const int row = k - (cell - p);  // B_k among the active splines cell - p .. cell
      const Eigen::Index i = level.index(k);
      const int wrapped =
          level.periodic() ? ((cell % level.cells()) + level.cells()) % level.cells() : cell;
      for (int m = 0; m < local; ++m) {
        const Eigen::Index sample = i * local + m;
        out.samples()[static_cast<std::size_t>(sample)] =
            (wrapped + (m + 0.5) / local) * level.cell_width();
        out.weights()(i, sample) = inverse(row, m);
      }
    }
  }
};

}  // namespace
}  // namespace rkhs

RKHS_REGISTER_PROJECTION(rkhs::Interpolation)
RKHS_REGISTER_PROJECTION(rkhs::MraLevel)
RKHS_REGISTER_PROJECTION(rkhs::L2Projection)
RKHS_REGISTER_PROJECTION(rkhs::QuasiInterpolant)
