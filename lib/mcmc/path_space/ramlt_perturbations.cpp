#include "lib/mcmc/path_space/ramlt_perturbations.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lib/geometry/spawn.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/mcmc/path_space/ramlt_direction.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"

namespace tb::path_space {

namespace {

// The first chain from the camera along w: y_{k-1} and, through the specular chain of x, down to
// y_stop (non-specular). False when the chain changes or the ray escapes.
bool trace_from_camera(const PathContext& ctx, const MltPath& x, MltPath& y, const Vec3& w, int stop) {
  const int k = x.segments();
  const auto h = ctx.world->geometry().intersect(Ray{x.v[k].hit.p, w});
  if (!h) return false;
  y.v[k - 1] = surface_vertex(ctx, *h);
  if (k - 1 == stop) return !is_dirac_surface(y.v[k - 1]);
  if (!is_dirac_surface(y.v[k - 1])) return false;
  const auto s = dirac_lobe_sample(y.v[k - 1], -w, transmits_from_camera_side(x, k - 1), TransportMode::kRadiance);
  return s && trace_chain(ctx, x, y, k - 1, s->wi, stop);
}

// p_w of the primary direction converted to the area of y_{k-1}.
double primary_area_density(const MltPath& x, const MltPath& y, double sigma) {
  const int k = x.segments();
  const double t = TruncatedNormalDirection::angle(RamltLensPerturbation::primary_direction(x),
                                                   RamltLensPerturbation::primary_direction(y));
  return solid_angle_to_area(TruncatedNormalDirection::density(t, sigma), y.v[k].hit.p, y.v[k - 1].hit.p,
                             y.v[k - 1].geometric_normal());
}

}  // namespace

ScreenPartition::ScreenPartition(const PathContext& ctx, std::shared_ptr<const ScreenCellPartition> cells)
    : ctx_(&ctx), cells_(std::move(cells)) {}

std::shared_ptr<const ScreenPartition> ScreenPartition::make(const PathContext& ctx, const std::string& name, int n) {
  mcmc::PartitionBox<2> box{{0.0, 0.0}, {1.0, 1.0}, {n, n}};
  return std::make_shared<const ScreenPartition>(ctx, mcmc::make_partition<2>(name, box));
}

std::array<double, 2> ScreenPartition::canonical(const MltPath& x) const {
  const auto r = path_raster(*ctx_, x);
  if (!r) return {0.0, 0.0};
  const Camera& cam = ctx_->world->camera();
  return {r->x / cam.width(), r->y / cam.height()};
}

int ScreenPartition::region_of(const MltPath& x) const {
  if (cells_->regions() == 1) return 0;
  return cells_->region_of(canonical(x));
}

double RegionalScale::sigma_of_region(int r) const { return std::exp(0.5 * (*lambda)[static_cast<size_t>(r)]); }
double RegionalScale::sigma2_of_region(int r) const { return std::exp(0.5 * (*lambda2)[static_cast<size_t>(r)]); }

std::array<double, 2> cylindrical(const Vec3& w) {
  double phi = std::atan2(w.y, w.x);
  if (phi < 0.0) phi += 2.0 * kPi;
  return {std::clamp(0.5 * (w.z + 1.0), 0.0, 1.0), phi / (2.0 * kPi)};
}

int first_non_specular(const MltPath& x) {
  const int k = x.segments();
  if (k < 2) return -1;
  int j = k - 1;
  while (j >= 1 && is_dirac_surface(x.v[j])) --j;
  return j >= 1 && !is_dirac_surface(x.v[j]) ? j : -1;
}

Screen4dPartition::Screen4dPartition(const PathContext& ctx, std::shared_ptr<const DirectionCellPartition> cells)
    : ctx_(&ctx), cells_(std::move(cells)) {}

std::shared_ptr<const Screen4dPartition> Screen4dPartition::make(const PathContext& ctx, const std::string& name,
                                                                 int n_top, int n_bottom) {
  mcmc::PartitionBox<4> box{{0.0, 0.0, 0.0, 0.0}, {1.0, 1.0, 1.0, 1.0}, {n_top, n_top, n_bottom, n_bottom}};
  return std::make_shared<const Screen4dPartition>(ctx, mcmc::make_partition<4>(name, box));
}

std::array<double, 4> Screen4dPartition::canonical(const MltPath& x) const {
  std::array<double, 4> c{0.0, 0.0, 0.0, 0.0};
  if (const auto r = path_raster(*ctx_, x)) {
    const Camera& cam = ctx_->world->camera();
    c[0] = r->x / cam.width();
    c[1] = r->y / cam.height();
  }
  const int j = first_non_specular(x);
  if (j >= 1) {
    const auto cy = cylindrical(direction(x.v[j], x.v[j - 1]));
    c[2] = cy[0];
    c[3] = cy[1];
  }
  return c;
}

RegionalScale RegionalScale::uniform(std::shared_ptr<const ScreenPartition> p, double lambda0) {
  const int n = p->regions();
  return {std::move(p), std::make_shared<const std::vector<double>>(static_cast<size_t>(n), lambda0)};
}

// ---- lens ----------------------------------------------------------------------------------------

Vec3 RamltLensPerturbation::primary_direction(const MltPath& x) {
  const int k = x.segments();
  return glm::normalize(x.v[k - 1].hit.p - x.v[k].hit.p);
}

std::optional<MltPath> RamltLensPerturbation::perturb(const MltPath& x, const Vec3& w) const {
  if (!applicable(x)) return std::nullopt;
  MltPath y = x;
  if (!trace_from_camera(*ctx_, x, y, w, lens_.chain_end(x))) return std::nullopt;
  if (!path_raster(*ctx_, y)) return std::nullopt;  // off the image: W_e = 0
  return y;
}

std::optional<MltPath> RamltLensPerturbation::propose(const MltPath& x, Uniforms& u) const {
  const Vec2 ud = u.next2();
  if (!applicable(x)) return std::nullopt;
  return perturb(x, TruncatedNormalDirection::sample(primary_direction(x), ud, scale_.sigma(x)));
}

double RamltLensPerturbation::density_with(const MltPath& x, const MltPath& y, double sigma) const {
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return 0.0;
  const int j = lens_.chain_end(x);
  if (lens_.chain_end(y) != j) return 0.0;
  for (int i = 0; i <= k; ++i)
    if ((i < j || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  for (int i = k - 1; i > j; --i)
    if (transmits_from_camera_side(x, i) != transmits_from_camera_side(y, i)) return 0.0;
  if (!path_raster(*ctx_, x) || !path_raster(*ctx_, y)) return 0.0;
  double t = primary_area_density(x, y, sigma);
  for (int i = k - 1; i > j; --i)
    t *= pdf_next_dirac(*ctx_, &y.v[i + 1], y.v[i], y.v[i - 1], TransportMode::kRadiance, DiracLobeChoice::kKept);
  return t;
}

// ---- multi-chain ---------------------------------------------------------------------------------

std::optional<MltPath> RamltMultiChainPerturbation::perturb(const MltPath& x, const Vec3& primary,
                                                            const std::vector<Vec3>& level_dirs) const {
  const std::vector<int> lv = multi_.levels(x);
  if (lv.empty() || level_dirs.size() + 1 < lv.size()) return std::nullopt;
  MltPath y = x;
  if (!trace_from_camera(*ctx_, x, y, primary, lv[0])) return std::nullopt;
  for (size_t m = 0; m + 1 < lv.size(); ++m) {
    const int i = lv[m];
    const Vec3 wx = apex_direction(x, i), wy = level_dirs[m];
    // The scattering side at y_i must be that of x_i (reflection / transmission kept).
    const Vec3 cx = direction(x.v[i], x.v[i + 1]), cy = direction(y.v[i], y.v[i + 1]);
    const bool tx = glm::dot(cx, x.v[i].hit.ng) * glm::dot(wx, x.v[i].hit.ng) < 0;
    const bool ty = glm::dot(cy, y.v[i].hit.ng) * glm::dot(wy, y.v[i].hit.ng) < 0;
    if (tx != ty) return std::nullopt;
    if (!trace_chain(*ctx_, x, y, i, wy, lv[m + 1])) return std::nullopt;
  }
  if (!path_raster(*ctx_, y)) return std::nullopt;
  return y;
}

std::optional<MltPath> RamltMultiChainPerturbation::propose(const MltPath& x, Uniforms& u) const {
  // A fixed number of uniforms per path length: one pair for the primary direction, one per segment.
  const Vec2 up = u.next2();
  std::vector<Vec2> ul(static_cast<size_t>(std::max(0, x.segments())));
  for (auto& v : ul) v = u.next2();
  const std::vector<int> lv = multi_.levels(x);
  if (lv.empty()) return std::nullopt;
  const double sigma = scale_.sigma(x), sigma2 = scale_.sigma2(x);  // sigma_1, sigma_2 (Otsu Sec. 5.2)
  const Vec3 primary = TruncatedNormalDirection::sample(RamltLensPerturbation::primary_direction(x), up, sigma);
  // Level m perturbs the direction at the NEW vertex y_{jm} around x's direction there (as
  // multi_chain_perturbation.cpp): known before tracing, since the frame is that of x.
  std::vector<Vec3> dirs;
  for (size_t m = 0; m + 1 < lv.size(); ++m)
    dirs.push_back(TruncatedNormalDirection::sample(apex_direction(x, lv[m]), ul[m], sigma2));
  return perturb(x, primary, dirs);
}

double RamltMultiChainPerturbation::density_with(const MltPath& x, const MltPath& y, double sigma,
                                                 double sigma2) const {
  const int k = x.segments();
  if (y.segments() != k) return 0.0;
  const std::vector<int> lx = multi_.levels(x), ly = multi_.levels(y);
  if (lx.empty() || lx != ly) return 0.0;
  const int last = lx.back();
  for (int i = 0; i <= k; ++i)
    if ((i < last || i == k) && !same_vertex(x.v[i], y.v[i])) return 0.0;
  for (int i = last + 1; i < k; ++i)
    if (is_dirac_surface(x.v[i]) && transmits_from_camera_side(x, i) != transmits_from_camera_side(y, i)) return 0.0;
  if (!path_raster(*ctx_, x) || !path_raster(*ctx_, y)) return 0.0;
  double t = primary_area_density(x, y, sigma);
  for (int i = k - 1; i > last; --i) {
    if (is_dirac_surface(y.v[i])) {
      t *= pdf_next_dirac(*ctx_, &y.v[i + 1], y.v[i], y.v[i - 1], TransportMode::kRadiance, DiracLobeChoice::kKept);
      continue;
    }
    const Vec3 wx = apex_direction(x, i), wy = apex_direction(y, i);
    const Vec3 o = spawn_ray(y.v[i].hit, direction(y.v[i], y.v[i - 1])).o;
    t *= solid_angle_to_area(TruncatedNormalDirection::density(TruncatedNormalDirection::angle(wx, wy), sigma2), o,
                             y.v[i - 1].hit.p, y.v[i - 1].geometric_normal());
  }
  return t;
}

}  // namespace tb::path_space
