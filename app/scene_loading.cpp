#include "app/scene_loading.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "lib/core/atomic_file.h"
#include "lib/scene/scene_loader.h"

namespace tb {

std::pair<int, int> parse_resolution(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w <= 0 || h <= 0)
    throw std::invalid_argument("--resolution '" + s + "': expected WxH with positive integers, e.g. 512x512");
  return {w, h};
}

std::unique_ptr<World> load_scene_file(const std::string& path, const std::string& resolution) {
  if (resolution.empty()) return load_world(path);
  const auto [w, h] = parse_resolution(resolution);
  nlohmann::json j = scene_json_from_file(path);  // JSON, or Mitsuba XML translated
  if (!j.is_object() || !j.contains("camera") || !j["camera"].is_object())
    throw std::invalid_argument(path + ": no camera object to set the resolution of");
  j["camera"]["resolution"] = {w, h};
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return load_world_from_string(j.dump(1), path, parent.empty() ? "." : parent.string());
}

RenderSettings fixed_work_settings(const World& world, int64_t spp, int64_t passes, uint64_t seed) {
  RenderSettings st;
  st.seed = seed;
  st.spp = spp > 0 ? spp : world.integrator_defaults().value("spp", int64_t{16});
  st.max_depth = world.integrator_defaults().value("max_depth", 10);
  st.passes = std::min(passes, st.spp);
  return st;
}

// Samples per pixel per pass of a time-budgeted run (see scene_loading.h): 1, except for the
// integrators on the primary-sample-space driver and apt, whose every pass starts with a bootstrap
// of at least 8192 samples (PssSettings::bootstrap_for, AptSettings::bootstrap_for): n = ceil(65536 / P), so that a pass's mutations
// are at least eight times its bootstrap (at 256 x 256 and above, one mutation per pixel per
// pass; at 128 x 128, four); and
// multi-stage MLT, whose every pass also builds its guide images from scratch: n = ceil(131072 / P)
// (8 at 128 x 128), so that the guides are not mostly noise (measured, docs/compare.md).
int64_t default_pass_spp(const std::string& integrator, int64_t pixels) {
  const auto at_least = [pixels](int64_t mutations) { return std::max<int64_t>(1, (mutations + pixels - 1) / pixels); };
  if (integrator.rfind("msmlt", 0) == 0) return at_least(131072);
  for (const char* prefix : {"pssmlt", "mmlt", "apt"})
    if (integrator.rfind(prefix, 0) == 0) return at_least(65536);
  return 1;
}

}  // namespace tb
