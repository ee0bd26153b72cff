// The cost of the sparse path predicted before anything is built (rkhs/approx/sparse_gram.hpp):
// the nonzeros of the Gram matrix from the volume of the kernel's support, and those of its
// Cholesky factor and the factorisation's flops from a geometric nested dissection of the
// domain, the ordering CHOLMOD's METIS finds on such a graph.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "rkhs/approx/sparse_gram.hpp"

namespace rkhs {

namespace {

// A box of the dissection, in units of the centre spacing: its extent per axis and whether each
// of its two faces per axis is interior (it borders points eliminated later: the separators of
// its ancestors, or the other side of a periodic seam).
struct Box {
  int dimension = 1;
  std::array<double, Domain::max_dimension> extent{1, 1, 1};
  std::array<std::array<bool, 2>, Domain::max_dimension> interior{};

  double points() const {
    double p = 1;
    for (int a = 0; a < dimension; ++a) p *= extent[a];
    return p;
  }
  // The area of the face across axis `across`.
  double face(int across) const {
    double p = 1;
    for (int a = 0; a < dimension; ++a)
      if (a != across) p *= extent[a];
    return p;
  }
};

struct FactorCost {
  double nonzeros = 0, flops = 0;
};

// A front of s columns eliminated together, coupled to b rows eliminated later: its dense
// triangle and its b x s block, and the flops of their factorisation and of the rank-s update
// of the b x b Schur complement.
FactorCost front(double s, double b) {
  return {s * (s + 1) / 2 + s * b, s * s * s / 3 + s * s * b + s * b * b};
}

// The points eliminated after `box` within `reach` of it: a layer over its interior faces.
double boundary(const Box& box, double reach) {
  double points = 0;
  for (int a = 0; a < box.dimension; ++a)
    for (const bool side : box.interior[a])
      if (side) points += reach * box.face(a);
  return points;
}

// Nested dissection of `box` with neighbours within `reach` spacings: a slab of thickness
// `reach` across its longest axis separates two halves, which are dissected alike; a box of a
// few points, or one the slab would fill, is one front. The halves mirror each other (the face
// the slab leaves them is interior; the other is the parent's), so one is dissected and doubled.
FactorCost dissect(const Box& box, double reach, double total) {
  int longest = 0;
  for (int a = 1; a < box.dimension; ++a)
    if (box.extent[a] > box.extent[longest]) longest = a;
  const double thickness = std::clamp(reach, 1.0, box.extent[longest]);
  if (box.points() <= 64 || box.extent[longest] - thickness < 2)
    return front(box.points(), std::min(boundary(box, reach), total));
  // Once the halves are eliminated, the separator is coupled to every point of the box's
  // interior faces (the halves' fill).
  const double coupled = boundary(box, reach);
  const FactorCost separator = front(thickness * box.face(longest), std::min(coupled, total));
  Box half = box;
  half.extent[longest] = (box.extent[longest] - thickness) / 2;
  half.interior[longest] = {box.interior[longest][0], true};
  const FactorCost halves = dissect(half, reach, total);
  return {separator.nonzeros + 2 * halves.nonzeros, separator.flops + 2 * halves.flops};
}

}  // namespace

double predicted_gram_nonzeros(const KernelProperties& properties, const Domain& domain,
                               std::size_t n) {
  const double count = static_cast<double>(n);
  const double rho = properties.support_radius;
  if (!(rho > 0) || !std::isfinite(rho)) return count * count;
  const double support = domain.dimension == 1   ? 2 * rho
                         : domain.dimension == 2 ? std::numbers::pi * rho * rho
                                                 : 4.0 / 3.0 * std::numbers::pi * rho * rho * rho;
  return count + count * (count - 1) * std::min(1.0, support / domain.volume());
}

SparseFactorPrediction predict_sparse_factor(const KernelProperties& properties,
                                             const Domain& domain, std::size_t n) {
  SparseFactorPrediction out;
  const double count = std::max(1.0, static_cast<double>(n));
  out.gram_nonzeros = predicted_gram_nonzeros(properties, domain, n);
  const double rho = properties.support_radius;
  if (!(rho > 0) || !std::isfinite(rho)) {
    out.factor_nonzeros = count * (count + 1) / 2;
    out.factor_flops = count * count * count / 3;
    return out;
  }
  // Quasi-uniform centres: spacing h with n h^d = |Omega|.
  const double spacing = std::pow(domain.volume() / count, 1.0 / domain.dimension);
  Box box;
  box.dimension = domain.dimension;
  for (int a = 0; a < domain.dimension; ++a) {
    box.extent[a] = std::max(1.0, domain.extent(a) / spacing);
    box.interior[a] = {domain.periodic, domain.periodic};
  }
  const FactorCost cost = dissect(box, rho / spacing, count);
  out.factor_nonzeros = std::min(cost.nonzeros, count * (count + 1) / 2);
  out.factor_flops = std::min(cost.flops, count * count * count / 3);
  return out;
}

}  // namespace rkhs
