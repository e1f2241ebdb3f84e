// Loading a scene file for the program's subcommands (`tb render`, `tb compare SCENE`), with the
// camera resolution optionally overridden from the command line ("WxH"); and the pass size of
// time-budgeted runs, shared by both.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

// "WxH" -> (W, H); throws std::invalid_argument on anything else (naming the option text).
std::pair<int, int> parse_resolution(const std::string& s);

// The scene file; when `resolution` is not empty, the camera's "resolution" is replaced by it
// before the scene is built (relative paths in the file still resolve against its folder).
std::unique_ptr<World> load_scene_file(const std::string& path, const std::string& resolution);

// The settings of a fixed-work render, as `tb render` and the Python module's render() make them:
// spp samples per pixel (0: the scene's "integrator.spp", else 16), the scene's max_depth (else
// 10), `passes` passes (at most spp).
RenderSettings fixed_work_settings(const World& world, int64_t spp, int64_t passes, uint64_t seed);

// Time-budgeted runs use open-ended passes (far more than any budget reaches) of n samples per
// pixel each, spp = n * passes: n samples per pixel for path tracing, light tracing and BDPT; n P
// mutations after a bootstrap for the primary-sample-space MCMC integrators (P = pixel count);
// one chain of n P mutations for path-space MLT. n = 1, except for the primary-sample-space
// integrators, whose pass starts with a bootstrap of at least 8192 samples: n = ceil(65536 / P),
// and multi-stage MLT, whose pass also builds its guides: n = ceil(131072 / P).
int64_t default_pass_spp(const std::string& integrator, int64_t pixels);

}  // namespace tb
