// Loading a scene file for the program's subcommands, with the camera resolution optionally
// overridden from the command line ("WxH"). Used by `tb compare SCENE ...`; `tb render` keeps
// its own copy of the same two steps (app/cmd_render.cpp) and can switch to this helper.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "lib/scene/world.h"

namespace tb {

// "WxH" -> (W, H); throws std::invalid_argument on anything else (naming the option text).
std::pair<int, int> parse_resolution(const std::string& s);

// The scene file; when `resolution` is not empty, the camera's "resolution" is replaced by it
// before the scene is built (relative paths in the file still resolve against its folder).
std::unique_ptr<World> load_scene_file(const std::string& path, const std::string& resolution);

}  // namespace tb
