// tb render: renders a scene file with a named integrator to OpenEXR (with the Welch
// statistics channels) and a tone-mapped PNG preview, plus a JSON record of the run.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace tb {

struct RenderArgs {
  std::string scene;
  std::string integrator = "albedo";
  int64_t spp = 0;          // 0: the scene's default, else 16
  int64_t passes = 8;
  double time_s = 0;
  uint64_t seed = 1;
  int threads = 0;
  std::string out = "out.exr";
  std::string resolution;   // "WxH": overrides the camera resolution of the scene file
  bool no_progress = false;
  bool list = false;
  std::string partition;    // ramlt-*: fixed | global | grid | quadtree (default grid)
  std::vector<std::string> params;  // NAME=VALUE, integrator parameters
};

int cmd_render(const RenderArgs& a, const std::atomic<bool>* interrupted);

}  // namespace tb
