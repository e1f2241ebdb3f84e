// Veach's lens perturbation (Veach 1997, Sec. 11.4.3; Veach & Guibas 1997, Sec. 5.3.1) on the
// shared path representation: the image-plane position of the path moves by an offset drawn
// from a symmetric kernel in raster space, the camera ray through the new position gives a new
// x'_{k-1}, which is joined to the kept x_{k-2} (or, for k = 1, is itself the emitter point).
// Only the lens subpath x_{k-1} x_k changes: paths here have no specular vertices
// (path_state.h), so the "retrace through specular vertices" of Veach's (L|D)DS*E lens subpaths
// is the empty chain.
//
// Kernel (Veach 1997, Sec. 11.4.3): offset at angle phi = 2 pi u1, radius
//   r = r2 exp(-ln(r2 / r1) u2),  r1 <= r <= r2,
// i.e. the raster density K(d) = 1 / (2 pi |d|^2 ln(r2 / r1)) on the annulus r1 <= |d| <= r2,
// symmetric: K(d) = K(-d). Defaults r1 = 0.1 pixel, r2 = 10% of the larger image side
// (Veach: "r2 = 10% of the image size").
//
// Density in the path measure: y differs from x in y_{k-1} only, so T is a density w.r.t. area at
// y_{k-1}: T(x -> y) = K(r(y) - r(x)) |d r / d A(y_{k-1})|, and |dr / dA| = P pE_y(k-1) with P the
// pixel count and pE_y(k-1) = pdf_next(camera -> y_{k-1}) (Camera::pdf_we is the density of a
// uniform raster position over the whole image, 1 / P, times dr / dA). Hence
//   T(y -> x) / T(x -> y) = pE_x(k-1) / pE_y(k-1)
// (the kernel cancels), which is the Jacobian between raster and path measure; see
// docs/mlt-path-space.md for the derivation.
#pragma once

#include <optional>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

enum class LensFault {
  kNone,
  kDropDensityRatio,  // negative control: T stated as a constant, so a = min(1, f(y) / f(x))
};

class LensPerturbation {
 public:
  using State = MltPath;
  // r1, r2 in pixels; r2 <= 0: 10% of the larger image side.
  LensPerturbation(const PathContext& ctx, double r1 = 0.1, double r2 = 0.0, LensFault fault = LensFault::kNone);

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;

  // Can the perturbation act on x (k >= 1, nothing Dirac at x_{k-1}; for k = 1, x_0 on an area
  // emitter, whose perturbed replacement is the surface point the new camera ray hits)?
  bool applicable(const MltPath& x) const;
  // The raster offset drawn from two uniforms, and the kernel density K(d) (per raster area).
  Vec2 sample_offset(const Vec2& u) const;
  double kernel_density(const Vec2& d) const;
  // y from x with a given raster offset (nothing when off the image or the ray escapes).
  std::optional<MltPath> perturb(const MltPath& x, const Vec2& offset) const;
  // |d raster / d A(x_{k-1})| = P pE(k-1).
  double raster_jacobian(const MltPath& x) const;
  double r1() const { return r1_; }
  double r2() const { return r2_; }

 private:
  const PathContext* ctx_;
  double r1_, r2_;
  LensFault fault_;
};

}  // namespace tb::path_space
