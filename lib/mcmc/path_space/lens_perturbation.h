// Veach's lens perturbation (Veach 1997, Sec. 11.4.3; Veach & Guibas 1997, Sec. 5.3.1) on the
// shared path representation: the image-plane position of the path moves by an offset drawn
// from a symmetric kernel in raster space, the camera ray through the new position is traced
// through the specular chain x_{k-1} .. x_{j+1} of x (Dirac vertices, lib/path/dirac.h, each with
// the lobe it has in x: reflection or transmission) to the first non-specular vertex y_j, which is
// joined to the kept x_{j-1} (for j = 0, y_j is itself the emitter point). Veach's lens subpaths
// are (L|D)DS*E: x_j non-specular, x_{j-1} non-specular (or the emitter). The move fails when the
// traced chain changes: a vertex of the chain is not specular, takes the other lobe, or y_j is.
//
// Kernel (Veach 1997, Sec. 11.4.3): offset at angle phi = 2 pi u1, radius
//   r = r2 exp(-ln(r2 / r1) u2),  r1 <= r <= r2,
// i.e. the raster density K(d) = 1 / (2 pi |d|^2 ln(r2 / r1)) on the annulus r1 <= |d| <= r2,
// symmetric: K(d) = K(-d). Defaults r1 = 0.1 pixel, r2 = 10% of the larger image side
// (Veach: "r2 = 10% of the image size").
//
// Density in the path measure: y differs from x in y_j .. y_{k-1} only; y_{k-1} has the area density
// K(r(y) - r(x)) |d r / d A(y_{k-1})| with |dr / dA| = P pE_y(k-1) (P the pixel count, pE_y(k-1) =
// pdf_next(camera -> y_{k-1}): Camera::pdf_we is the density of a uniform raster position over the
// whole image, 1 / P, times dr / dA), and each vertex after a specular one the pseudo density of
// lib/path/dirac.h with the lobe kept (P(lobe) = 1, radiance mode: delta dropped, the solid angle
// converted to area at y_{i-1}):
//   T(x -> y) = K(r(y) - r(x)) P pE_y(k-1) prod_{i=j+1}^{k-1} |cos y_{i-1}| / |y_i - y_{i-1}|^2.
// The kernel cancels in T(y -> x) / T(x -> y), which is the ratio of the Jacobians from raster to
// path measure (raster_jacobian); see docs/mlt-path-space.md.
#pragma once

#include <optional>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

class LensPerturbation {
 public:
  using State = MltPath;
  // r1, r2 in pixels; r2 <= 0: 10% of the larger image side.
  LensPerturbation(const PathContext& ctx, double r1 = 0.1, double r2 = 0.0);

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;

  // Can the perturbation act on x (k >= 1, a lens subpath (L|D)DS*E; for j = 0, x_0 on an area
  // emitter, whose perturbed replacement is the surface point the traced ray hits)?
  bool applicable(const MltPath& x) const;
  // j: the first non-specular vertex from the camera (x_j .. x_{k-1} are replaced); -1 if none.
  int chain_end(const MltPath& x) const;
  // The raster offset drawn from two uniforms, and the kernel density K(d) (per raster area).
  Vec2 sample_offset(const Vec2& u) const;
  double kernel_density(const Vec2& d) const;
  // y from x with a given raster offset (nothing when off the image or the ray escapes).
  std::optional<MltPath> perturb(const MltPath& x, const Vec2& offset) const;
  // The tracing part of perturb without the applicability test (x_{j-1} may be specular): y with
  // y_j .. y_{k-1} traced through x's specular chain, the other vertices of x kept (the manifold
  // perturbation, manifold_perturbation.h, reconnects y_j to x_{j-1} by a walk instead).
  std::optional<MltPath> trace(const MltPath& x, const Vec2& offset) const;
  // |d raster / d mu(x_j .. x_{k-1})| = P pE(k-1) times the pseudo densities along the chain.
  double raster_jacobian(const MltPath& x) const;
  double r1() const { return r1_; }
  double r2() const { return r2_; }

 private:
  const PathContext* ctx_;
  double r1_, r2_;
};

}  // namespace tb::path_space
