// Integrators by name (`tb render --integrator NAME`): each is a function that renders passes
// of a World into a Film. Registered from their own .cpp files (STYLE.md: variants are
// separate registered components, not flags).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

struct IntegratorInfo {
  std::string name;
  std::string description;
  // Renders into the film; returns the number of passes (Welch samples per pixel) done.
  std::function<int64_t(const World&, const RenderSettings&, Film&)> render;
};

// The registered integrators, sorted by name.
const std::vector<IntegratorInfo>& integrators();
const IntegratorInfo* find_integrator(const std::string& name);

}  // namespace tb
