// Import of scenes in the JSON format of the Tungsten renderer, for the subset this project's
// shapes, materials, lights and cameras cover (docs/scene.md, "Importing Tungsten scenes"):
// quad and cube primitives with position / rotation / scale transforms, lambert and null BSDFs,
// emissive quads, the pinhole camera, the path tracer's max_bounces and the renderer's spp.
// The import translates the Tungsten document into a document of this project's format, which
// the ordinary scene loader then builds. Anything outside the subset is a JsonError naming the
// file, the line, the element's path (e.g. `primitives[3].bsdf.type = "plastic"`) and what is
// not supported; nothing is dropped or approximated silently.
#pragma once

#include <memory>

#include <nlohmann/json.hpp>

#include "lib/core/strict_json.h"

namespace tb {

// A Tungsten scene has top-level "primitives", "bsdfs" or "renderer" and neither of this
// format's "shapes" and "materials".
bool is_tungsten_scene(const nlohmann::json& root);

// The scene in this project's format (docs/scene.md, "Format"). Throws JsonError.
nlohmann::json tungsten_to_scene_json(const JsonDocument& doc);

}  // namespace tb
