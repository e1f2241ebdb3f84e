// BSDFs by name, for the scene parser: make_bsdf("rough_dielectric", {"distribution": "ggx",
// "alpha": 0.1, "eta": 1.5}). Parameters are strict: an unknown or ill-typed key is an error that
// names it (STYLE.md, "Settings are strict"). Roughness "alpha" is Beckmann-equivalent
// (lib/core/microfacet.h).
//
//   lambert            reflectance [r,g,b] (default [0.5,0.5,0.5])
//   smooth_conductor   eta [r,g,b], k [r,g,b] (default: gold-like 0.2/0.92/1.1, 3.9/2.45/2.14)
//   smooth_dielectric  eta (default 1.5)
//   rough_conductor    eta, k, distribution ("beckmann" | "ggx", default ggx), alpha (default 0.1),
//                      visible_normals (bool, ggx only, default false)
//   rough_dielectric   eta, distribution, alpha, visible_normals
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/material/bsdf.h"

namespace tb {

// Throws std::invalid_argument for an unknown name or parameter.
std::unique_ptr<Bsdf> make_bsdf(std::string_view name, const nlohmann::json& params = nlohmann::json::object());
// The registered names, in a fixed order.
std::vector<std::string> bsdf_names();

}  // namespace tb
