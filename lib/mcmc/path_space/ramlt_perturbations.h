// Otsu et al.'s regional adaptive path perturbations ("Regional Adaptive Metropolis Light
// Transport", Sec. 3 and 5): the lens and the multi-chain perturbation of Veach & Guibas with the
// primary ray direction (and, for the multi-chain perturbation, the direction leaving each
// continued non-specular vertex) perturbed by the truncated-normal direction kernel of
// ramlt_direction.h, whose scale sigma is that of the region of the CURRENT path (Otsu Eq. 2-3):
//   T(x -> .) = sum_k 1_{P_k}(x) T(. | x, sigma_k).
// So T(x -> y) uses sigma of x's region and T(y -> x) sigma of y's region; a move across a region
// boundary does not cancel the kernel in the Hastings ratio.
//
// The partition (Otsu Sec. 5.4, "2d Partition for the Lens Perturbation"): P_k = paths whose raster
// position rp(w_{x1 -> x2}), normalised to [0, 1]^2, lies in S_k, S_k the cells of a partition of
// estimators/mcmc/partition.h (fixed, global, grid, quadtree; Otsu Sec. 6.1-6.2).
//
// The multi-chain perturbation has two scales, sigma-bar = (sigma_1, sigma_2) (Otsu Sec. 5.2):
// sigma_1 for the primary ray direction, sigma_2 for the direction leaving the first non-specular
// vertex x_c (and, our choice, every further continued level). With a 2d partition both are the
// sigma of x's screen region. With the 4d partition (Otsu Sec. 5.4, Eq. 7; Sec. 6.3, Fig. 7;
// Screen4dPartition) sigma_1 is the sigma of x's top-level screen cell S_l and sigma_2 that of x's
// 4d region S_l x T_j, T_j a cell (grid4d) or a quadtree leaf (quadtree4d) of the cylindrical
// direction cy(w_{x_c -> x_{c+1}}) (Otsu Sec. 8.1 / Fig. 6: the top-level grid belongs to the
// primary direction, the bottom level to the secondary one).
//
// Densities in the path measure (lib/path/dirac.h pseudo densities, radiance mode, lobe kept):
//   lens:  T(x -> y) = p_w(w_y | w_x, sigma(x)) |cos y_{k-1}| / |y_{k-1} - y_k|^2
//                      prod_{i=j+1}^{k-1} (pseudo density of y_{i-1} after the specular y_i),
//   multi-chain: the same for the first chain, times at every continued level m
//                      p_w(w_y,m | w_x,m, sigma(x)) |cos y_{jm-1}| / |o_y - y_{jm-1}|^2 prod_{chain m+1},
// w the primary ray direction x_k -> x_{k-1} (resp. the direction leaving the continued vertex's
// spawn apex). The structure conditions (applicable paths, kept vertices, lobes) are those of
// lens_perturbation.h and multi_chain_perturbation.h.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mcmc/partition.h"
#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/mcmc/path_space/path_mutations.h"

namespace tb::path_space {

using ScreenCellPartition = mcmc::RegionPartition<std::array<double, 2>>;

// Path-space partition through the normalised raster position (Otsu Sec. 5.4).
class ScreenPartition {
 public:
  ScreenPartition(const PathContext& ctx, std::shared_ptr<const ScreenCellPartition> cells);
  // "fixed", "global", "grid" (n x n cells over [0, 1]^2; Otsu Sec. 8.1: N_top = 20) or
  // "quadtree" (the root only: the driver of ramlt.h builds and refines its own tree).
  static std::shared_ptr<const ScreenPartition> make(const PathContext& ctx, const std::string& name, int n = 20);
  int regions() const { return cells_->regions(); }
  bool adapts() const { return cells_->adapts(); }
  std::string name() const { return cells_->name(); }
  // The region of x; a path without raster position (never a state of positive target) is in
  // the region of raster (0, 0).
  int region_of(const MltPath& x) const;
  std::array<double, 2> canonical(const MltPath& x) const;

 private:
  const PathContext* ctx_;
  std::shared_ptr<const ScreenCellPartition> cells_;
};

using DirectionCellPartition = mcmc::RegionPartition<std::array<double, 4>>;

// cy(w) of Otsu Eq. 7: the direction in 2d cylindrical coordinates, ((w_z + 1) / 2, phi / 2 pi)
// in [0, 1]^2 (Lambert's equal-area map: equal cells hold equal solid angle).
std::array<double, 2> cylindrical(const Vec3& w);
// x_c of Otsu Sec. 5.4: the index of the first non-specular vertex after the camera (x.v[k] the
// camera, x.v[k - 1] the first hit); -1 when there is none with a vertex after it.
int first_non_specular(const MltPath& x);

// Path-space partition through (rp(w_{x1 -> x2}) / (W, H), cy(w_{x_c -> x_{c+1}})) in [0, 1]^4
// (Otsu Sec. 5.4, Eq. 7). A path without raster position is at raster (0, 0), one without x_c at
// direction (0, 0).
class Screen4dPartition {
 public:
  Screen4dPartition(const PathContext& ctx, std::shared_ptr<const DirectionCellPartition> cells);
  // "grid4d" (n_top^2 screen cells x n_bottom^2 direction cells; Otsu Sec. 8.1: 20, 50) or
  // "quadtree4d" (n_top^2 screen cells, each a quadtree root: the driver refines its own).
  static std::shared_ptr<const Screen4dPartition> make(const PathContext& ctx, const std::string& name, int n_top,
                                                       int n_bottom);
  int regions() const { return cells_->regions(); }
  std::string name() const { return cells_->name(); }
  int region_of(const MltPath& x) const { return cells_->region_of(canonical(x)); }
  std::array<double, 4> canonical(const MltPath& x) const;

 private:
  const PathContext* ctx_;
  std::shared_ptr<const DirectionCellPartition> cells_;
};

// The scales the perturbations read: lambda_k = log sigma_k^2 per region (Otsu Sec. 5.3), owned by
// the driver, which changes them only between synchronous batches (ramlt.h). `partition` holds
// sigma_1 (and sigma_2 when `partition2` is empty); `partition2`, when set, the 4d regions of
// sigma_2 (Otsu Sec. 5.2, 5.4).
struct RegionalScale {
  std::shared_ptr<const ScreenPartition> partition;
  std::shared_ptr<const std::vector<double>> lambda;
  std::shared_ptr<const Screen4dPartition> partition2 = nullptr;
  std::shared_ptr<const std::vector<double>> lambda2 = nullptr;
  int region(const MltPath& x) const { return partition->region_of(x); }
  double sigma_of_region(int r) const;
  double sigma(const MltPath& x) const { return sigma_of_region(region(x)); }
  // The 4d region of x (-1 without a 4d partition) and sigma_2 of x.
  int region2(const MltPath& x) const { return partition2 ? partition2->region_of(x) : -1; }
  double sigma2_of_region(int r) const;
  double sigma2(const MltPath& x) const { return partition2 ? sigma2_of_region(region2(x)) : sigma(x); }
  // One region per partition cell, every lambda = lambda0.
  static RegionalScale uniform(std::shared_ptr<const ScreenPartition> p, double lambda0);
};

class RamltLensPerturbation {
 public:
  using State = MltPath;
  RamltLensPerturbation(const PathContext& ctx, RegionalScale scale) : ctx_(&ctx), lens_(ctx), scale_(std::move(scale)) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  // T(x -> y) with sigma of x's region (Otsu Eq. 2).
  double density(const MltPath& x, const MltPath& y) const { return density_with(x, y, scale_.sigma(x)); }
  // T(x -> y | x, sigma) for a given sigma (the per-region kernel T_k of Otsu Eq. 3).
  double density_with(const MltPath& x, const MltPath& y, double sigma) const;
  // T(x -> y) with the scale of the region of s (s = x: density; validate/ reads other s).
  double density_at(const MltPath& x, const MltPath& y, const MltPath& s) const {
    return density_with(x, y, scale_.sigma(s));
  }
  bool applicable(const MltPath& x) const { return lens_.applicable(x); }
  // y from x with the primary ray along w (nothing when off the image, escaped, or the chain changed).
  std::optional<MltPath> perturb(const MltPath& x, const Vec3& w) const;
  static Vec3 primary_direction(const MltPath& x);
  const RegionalScale& scale() const { return scale_; }

 private:
  const PathContext* ctx_;
  LensPerturbation lens_;
  RegionalScale scale_;
};

class RamltMultiChainPerturbation {
 public:
  using State = MltPath;
  RamltMultiChainPerturbation(const PathContext& ctx, RegionalScale scale)
      : ctx_(&ctx), multi_(ctx), scale_(std::move(scale)) {}
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  // T(x -> y) with sigma_1 and sigma_2 of x's regions (Otsu Eq. 2, Sec. 5.2).
  double density(const MltPath& x, const MltPath& y) const { return density_at(x, y, x); }
  double density_at(const MltPath& x, const MltPath& y, const MltPath& s) const {
    return density_with(x, y, scale_.sigma(s), scale_.sigma2(s));
  }
  // sigma1 for the primary direction, sigma2 for every continued level.
  double density_with(const MltPath& x, const MltPath& y, double sigma1, double sigma2) const;
  double density_with(const MltPath& x, const MltPath& y, double sigma) const { return density_with(x, y, sigma, sigma); }
  bool applicable(const MltPath& x) const { return multi_.applicable(x); }
  // y from the primary direction and one direction per continued level.
  std::optional<MltPath> perturb(const MltPath& x, const Vec3& primary, const std::vector<Vec3>& level_dirs) const;
  const RegionalScale& scale() const { return scale_; }

 private:
  const PathContext* ctx_;
  MultiChainPerturbation multi_;
  RegionalScale scale_;
};

// A regional adaptive perturbation as a registered mutation: weight w where it applies, 0 elsewhere
// (so a mixture with the bidirectional mutation falls back to it, Otsu Sec. 8.1), and the region's
// sigma as its scale.
template <class P>
class RamltMutation final : public PathMutation {
 public:
  RamltMutation(std::string name, double weight, P p) : name_(std::move(name)), weight_(weight), p_(std::move(p)) {}
  std::string name() const override { return name_; }
  double weight(const MltPath& x) const override { return p_.applicable(x) ? weight_ : 0.0; }
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const override { return p_.propose(x, u); }
  double density(const MltPath& x, const MltPath& y) const override { return p_.density(x, y); }
  double scale(const MltPath& x) const override { return p_.scale().sigma(x); }
  const P& proposal() const { return p_; }

 private:
  std::string name_;
  double weight_;
  P p_;
};

using RamltLensMutation = RamltMutation<RamltLensPerturbation>;
using RamltMultiChainMutation = RamltMutation<RamltMultiChainPerturbation>;

}  // namespace tb::path_space
