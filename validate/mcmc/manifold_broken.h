// The manifold perturbation (lib/mcmc/path_space/manifold_perturbation.h) for the checks of
// validate/checks/mcmc_memlt_checks.cpp:
//  - manifold_reference_density: T(x -> y) assembled independently of the mutation's density:
//    the lens part from LensPerturbation::density's factors, the generalised geometry term from
//    the DENSE Eq. 11 Jacobian (Eigen full-pivot LU instead of the block LU of Sec. 7) with the
//    Dirac factors recomputed here, the landing indicators from the mutation's walks;
//  - ManifoldBrokenDensity (negative controls of the pairwise checks), proposals unchanged:
//    kNoGeometryTerm, T stated without the generalised geometry term
//    |det J_S| prod 1 / (|dh/d omega_prev| |<h, n>|); kTransposedBlock, the geometry term with the C
//    blocks of the chain Jacobian taken from the transposed A blocks (a wrong Eq. 11 assembly).
#pragma once

#include <cmath>
#include <optional>

#include <Eigen/Dense>

#include "lib/differential/hslt_constraints.h"
#include "lib/material/half_vector.h"
#include "lib/mcmc/path_space/manifold_perturbation.h"

namespace tb::path_space {

enum class ManifoldGeometryFault { kNone, kTransposedBlock };

// |det J_S(y)| (dense, area measure) times the Dirac factors of every chain vertex.
inline double manifold_dense_geometry(const ManifoldPerturbation& m, const MltPath& y,
                                      ManifoldGeometryFault fault = ManifoldGeometryFault::kNone) {
  const std::optional<HsltPath> S = m.hslt().hslt_path(m.subpath(y));
  if (!S) return 0.0;
  HsltBlocks b = hslt_constraint_blocks(*S);
  if (fault == ManifoldGeometryFault::kTransposedBlock)
    for (int r = 0; r + 1 < b.size(); ++r) b.C[static_cast<size_t>(r)] = b.A[static_cast<size_t>(r + 1)].transpose();
  const Eigen::MatrixXd J = hslt_dense_jacobian(b);
  double g = std::abs(J.fullPivLu().determinant());
  for (int i = 1; i < S->segments(); ++i) {
    const HsltVertex& v = S->vertices[static_cast<size_t>(i)];
    const HsltHalfVector hv = hslt_half_vector(*S, i);
    g /= v.area_element() * half_vector_jacobian(hv.w_next, hv.w_prev, v.eta_next, v.eta_prev) * std::abs(glm::dot(hv.h, v.n));
  }
  return std::isfinite(g) ? g : 0.0;
}

inline double manifold_reference_density(const ManifoldPerturbation& m, const MltPath& x, const MltPath& y,
                                         ManifoldGeometryFault fault = ManifoldGeometryFault::kNone) {
  const ManifoldPerturbation::DensityParts p = m.density_parts(x, y);
  if (!p.structure || !p.forward_lands || !p.reverse_lands) return 0.0;
  return p.lens * manifold_dense_geometry(m, y, fault);
}

// The perturbation with T stated without the generalised geometry term, or with it from a wrong
// assembly (kTransposedBlock).
class ManifoldBrokenDensity {
 public:
  using State = MltPath;
  enum class Fault { kNoGeometryTerm, kTransposedBlock };
  ManifoldBrokenDensity(ManifoldPerturbation m, Fault f) : m_(std::move(m)), f_(f) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const { return m_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const {
    if (f_ == Fault::kTransposedBlock) return manifold_reference_density(m_, x, y, ManifoldGeometryFault::kTransposedBlock);
    const ManifoldPerturbation::DensityParts p = m_.density_parts(x, y);
    return p.structure && p.forward_lands && p.reverse_lands ? p.lens : 0.0;
  }
  bool applicable(const MltPath& x) const { return m_.applicable(x); }
  const ManifoldPerturbation& inner() const { return m_; }

 private:
  ManifoldPerturbation m_;
  Fault f_;
};

}  // namespace tb::path_space
