#pragma once
// A basis along a path made of another: r(s) = R phi(s), R a fixed matrix (rows x size of
// phi), evaluated through the inner basis's own mapped evaluation (KernelBasis::set_map), so a
// feature kernel computes it from its few active features. Allocates nothing per evaluation.

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <stdexcept>
#include <utility>

#include "rkhs/kernel/kernel.hpp"

namespace rkhs {

class MappedBasis final : public KernelBasis {
 public:
  using InnerFactory = std::function<std::unique_ptr<KernelBasis>()>;

  /// r = R phi, phi the values of the bases `make_inner` makes (R.cols() == their size): one
  /// for r itself, and one more for set_map's T r = (T R) phi.
  MappedBasis(InnerFactory make_inner, Eigen::MatrixXd R)
      : make_inner_(std::move(make_inner)), inner_(make_inner_()), R_(std::move(R)) {
    if (static_cast<std::size_t>(R_.cols()) != inner_->size())
      throw std::invalid_argument("MappedBasis: R needs one column per function of the basis");
    inner_->set_map(R_);
  }
  std::size_t size() const noexcept override { return static_cast<std::size_t>(R_.rows()); }
  void evaluate(double s, double* r) const override { inner_->evaluate_mapped(s, r); }
  void evaluate_derivative(double s, double* dr) const override {
    inner_->evaluate_mapped_derivative(s, dr);
  }
  void set_map(const Eigen::MatrixXd& map) override {
    mapped_ = make_inner_();
    mapped_->set_map(map * R_);
  }
  void evaluate_mapped(double s, double* out) const override {
    require_map();
    mapped_->evaluate_mapped(s, out);
  }
  void evaluate_mapped_derivative(double s, double* out) const override {
    require_map();
    mapped_->evaluate_mapped_derivative(s, out);
  }

 private:
  void require_map() const {
    if (!mapped_) throw std::logic_error("MappedBasis: evaluate_mapped before set_map");
  }
  InnerFactory make_inner_;
  std::unique_ptr<KernelBasis> inner_, mapped_;
  Eigen::MatrixXd R_;
};

}  // namespace rkhs
