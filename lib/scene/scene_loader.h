// The JSON scene format (docs/scene.md). Strict: an unknown key, a wrong type, a missing field,
// a non-finite number or degenerate geometry is a JsonError naming the file, the line and the
// JSON pointer of the offending value; a missing mesh file names its path. A scene file of the
// Tungsten renderer is recognised by its keys and imported (lib/scene/tungsten_import.h); a text
// starting with '<' is a Mitsuba XML scene, imported by lib/scene/mitsuba_import.h.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lib/core/strict_json.h"
#include "lib/geometry/transform.h"
#include "lib/scene/world.h"

namespace tb {

std::unique_ptr<World> load_world(const std::string& path);
// From text; relative mesh paths resolve against base_dir.
std::unique_ptr<World> load_world_from_string(const std::string& text, const std::string& name = "<string>",
                                              const std::string& base_dir = ".");

// The document of a scene file in this project's format: the JSON as written, or the
// translation of a Mitsuba XML file (relative mesh paths made absolute). Throws JsonError.
nlohmann::json scene_json_from_file(const std::string& path);

// {"matrix": [[...4], [...4], [...4]]} or any of {"translate": [x,y,z], "rotate": [[ax,ay,az,deg], ...],
// "scale": s | [sx,sy,sz]}, composed as translate * rotate_n * ... * rotate_1 * scale.
AffineTransform parse_transform(const StrictObject& o);

// The vocabulary of the format, as the parser accepts it (the feature-coverage check of the
// shipped scenes enumerates these, so a type added here needs a checked scene that uses it).
inline const std::vector<std::string>& scene_camera_types() {
  static const std::vector<std::string> v = {"pinhole", "thin_lens"};
  return v;
}
inline const std::vector<std::string>& scene_shape_types() {
  static const std::vector<std::string> v = {"sphere",     "disk",  "rectangle", "cylinder", "paraboloid",
                                             "torus",      "cube",  "mesh",      "obj"};
  return v;
}
inline const std::vector<std::string>& scene_light_types() {
  static const std::vector<std::string> v = {"point", "spot", "directional", "environment"};
  return v;
}

}  // namespace tb
