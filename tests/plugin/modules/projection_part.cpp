// A plugin module with a projection instead of a kernel: kernel interpolation at the centres in
// the plain form S = Y = the centres, E = I, W = G^-1 (an explicit inverse), so that a trial with
// it goes through the framework's generic measurement of a projection (measure_projection) while
// the built-in `interpolation` goes through the established interpolation path: the two must
// agree.
#include "rkhs/approx/projection.hpp"
#include "rkhs/plugin/module.hpp"

namespace {

class PlainInterpolation final : public rkhs::Projection {
 public:
  static rkhs::PluginInfo info() {
    return {"test_plain_interpolation", "kernel interpolation at the centres, W = G^-1", {}, {}};
  }
  explicit PlainInterpolation(const rkhs::ParameterSet&) {}
  rkhs::ProjectionProperties properties() const override {
    return {rkhs::ProjectionResolution::centres, true, true, 1.0, {}};
  }
  void check(const rkhs::AnyKernel&, std::size_t) const override {}
  void build(const rkhs::ProjectionRequest& request, rkhs::ProjectionOperator& out) const override {
    const auto n = request.centres.size();
    const Eigen::MatrixXd gram = request.kernel.gram(request.centres);
    out.resize(n, n, n);
    std::copy(request.centres.begin(), request.centres.end(), out.samples().begin());
    std::copy(request.centres.begin(), request.centres.end(), out.basis_points().begin());
    out.basis_coefficients().setIdentity();
    out.weights() = gram.llt().solve(Eigen::MatrixXd::Identity(gram.rows(), gram.cols()));
    out.set_mesh(request.centres);
    out.set_solve_method("cholesky (plugin)");
  }
};

}  // namespace

RKHS_REGISTER_PROJECTION(PlainInterpolation)
RKHS_PLUGIN_MODULE("projection_part")
