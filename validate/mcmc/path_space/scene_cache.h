// Scenes for the path-space MCMC checks, loaded once per (file, resolution) and kept for the run:
// the world, its light sampler and the PathContext over both.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "lib/path/light_sampler.h"
#include "lib/path/path.h"
#include "lib/scene/world.h"
#include "validate/render/render_compare.h"

namespace tb::path_space {

struct LoadedScene {
  std::unique_ptr<World> world;
  std::unique_ptr<LightSampler> lights;
  PathContext ctx;
};

inline const LoadedScene& cached_scene(const std::string& file, int resolution) {
  static std::mutex m;
  static std::map<std::pair<std::string, int>, std::unique_ptr<LoadedScene>> cache;
  const std::lock_guard<std::mutex> lock(m);
  auto& s = cache[{file, resolution}];
  if (!s) {
    s = std::make_unique<LoadedScene>();
    s->world = load_scene_at_resolution(file, resolution, resolution);
    s->lights = std::make_unique<LightSampler>(*s->world);
    s->ctx = PathContext{s->world.get(), s->lights.get()};
  }
  return *s;
}

}  // namespace tb::path_space
