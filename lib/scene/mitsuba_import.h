// Import of Mitsuba XML scenes (Mitsuba 0.6 and Mitsuba 3 share the format; docs/scene.md,
// "Importing Mitsuba scenes") for the subset this project's shapes, materials, lights and
// cameras model exactly: the perspective sensor with an hdrfilm and a box reconstruction filter,
// the sampler's sample count, the path and direct integrators, rectangle / disk / sphere / cube /
// obj shapes with translate / scale / rotate / matrix / lookat transforms, the diffuse, smooth
// conductor and smooth dielectric BSDFs (diffuse and conductor inside twosided), bsdf ids and
// refs, and area, point and constant emitters. The XML is parsed with pugixml and translated
// into a document of this project's format, which the ordinary scene loader then builds.
// Anything outside the subset, an unknown element or attribute, a malformed or non-finite
// number is a MitsubaError "file:LINE: <element ...>: what is unsupported"; nothing is
// dropped or approximated silently.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "lib/core/strict_json.h"

namespace tb {

// The importer's error. A JsonError, so that callers reporting scene errors catch both formats.
class MitsubaError : public JsonError {
 public:
  using JsonError::JsonError;
};

// True when the text is XML: its first character other than white space (and a UTF-8 byte
// order mark) is '<'. JSON scenes start with '{'.
bool is_mitsuba_scene(const std::string& text);

// The scene in this project's format (docs/scene.md, "Format"). `file` names the document in
// messages; relative OBJ file names resolve against base_dir (the XML file's folder), as in
// Mitsuba. Throws MitsubaError.
nlohmann::json mitsuba_to_scene_json(const std::string& text, const std::string& file, const std::string& base_dir);

}  // namespace tb
