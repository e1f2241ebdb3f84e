#include "app/cmd_compare.h"

#include <cctype>
#include <filesystem>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"
#include "lib/film/exr_io.h"
#include "validate/image_compare.h"

namespace tb {

namespace {

bool is_exr(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".exr";
}

WelchImage load_welch(const std::string& path) {
  const ExrImage e = read_exr(path);
  if (!e.variance || !e.count)
    fmt::print(stderr, "tb compare: warning: {} has no variance/count channels; treated as an exact reference\n", path);
  return welch_from_exr_image(e);
}

int compare_images(const CompareArgs& a) {
  const WelchImage img_a = load_welch(a.inputs[0]), img_b = load_welch(a.inputs[1]);
  const ImageCompareResult r = compare_welch_images(img_a, img_b, a.alpha);
  fmt::print("A: {}\nB: {}\n", a.inputs[0], a.inputs[1]);
  fmt::print("alpha {:g} (each of 3 tests {:.3g}, per pixel-channel {:.3g}); {} pixel-channels tested, {} identical "
             "skipped\n",
             r.alpha, r.alpha_each, r.alpha_pixel, r.tested, r.skipped_identical);
  fmt::print("  pixel-wise (Sidak over pixel-channels): p = {:.4g}{}\n", r.p_pixel_family,
             r.rejects_pixel() ? "  REJECTS" : "");
  static const char* kChannel[] = {"R", "G", "B"};
  auto ch = [](int c) { return c >= 0 && c < 3 ? kChannel[c] : "-"; };
  fmt::print("  Stouffer sum z / sqrt(P), worst channel {} = {:.4g}:   p = {:.4g} (Sidak over 3 channels){}\n",
             ch(r.stouffer_channel), r.stouffer.statistic, r.stouffer.p_value, r.rejects_stouffer() ? "  REJECTS" : "");
  fmt::print("  sum z^2, worst channel {} = {:.6g} (chi^2, {:.0f} dof):   p = {:.4g} (Sidak over 3 channels){}\n",
             ch(r.sum_z2_channel), r.sum_z2.statistic, r.sum_z2.dof, r.sum_z2.p_value,
             r.rejects_sum_z2() ? "  REJECTS" : "");
  if (r.zero_variance_mismatch > 0)
    fmt::print("  {} pixel-channels with zero variance in both images and different means\n", r.zero_variance_mismatch);
  if (r.skipped_below_float_range > 0)
    fmt::print("  {} pixel-channels skipped: means below 1.1e-19, whose variance a float EXR cannot hold\n",
               r.skipped_below_float_range);
  if (r.worst.x >= 0)
    fmt::print("  worst pixel ({}, {}) {}: A {:.6g}, B {:.6g}, t = {:.4g}, dof {:.4g}, p = {:.4g}\n", r.worst.x,
               r.worst.y, r.worst.channel >= 0 && r.worst.channel < 3 ? kChannel[r.worst.channel] : "?", r.worst.mean_a,
               r.worst.mean_b, r.worst.t, r.worst.dof, r.worst.p);
  fmt::print("  mean relative difference (A - B) / B: {:+.4g}\n", r.mean_relative_difference);
  fmt::print("{} (combined p = {:.4g})\n", r.rejects() ? "DIFFERENT" : "consistent", r.p_value());
  if (!a.json_out.empty()) {
    nlohmann::json j = r.details();
    j["a"] = a.inputs[0];
    j["b"] = a.inputs[1];
    j["rejects"] = r.rejects();
    write_file_atomic(a.json_out, j.dump(1));
  }
  return r.rejects() ? 1 : 0;
}

}  // namespace

int cmd_compare(const CompareArgs& a, const std::atomic<bool>* interrupted) {
  auto reject_options = [](const std::vector<std::string>& given, const char* form) {
    for (const auto& o : given) fmt::print(stderr, "tb compare: {} does not apply to the {} form\n", o, form);
    return given.empty();
  };
  if (a.inputs.size() == 1 && !is_exr(a.inputs[0])) {
    if (!reject_options(a.image_options_given, "scene")) return 2;
    CompareSceneArgs s = a.scene;
    s.scene = a.inputs[0];
    return cmd_compare_scene(s, interrupted);
  }
  if (a.inputs.size() == 2 && is_exr(a.inputs[0]) && is_exr(a.inputs[1])) {
    if (!reject_options(a.scene_options_given, "image (A.exr B.exr)")) return 2;
    if (!(a.alpha > 0 && a.alpha < 1)) {
      fmt::print(stderr, "tb compare: --alpha must lie in (0, 1)\n");
      return 2;
    }
    return compare_images(a);
  }
  fmt::print(stderr,
             "tb compare: expected two EXR images (tb compare A.exr B.exr [--alpha A]) or one scene file "
             "(tb compare SCENE --integrators A,B,... --time S [--reference REF.exr])\n");
  return 2;
}

}  // namespace tb
