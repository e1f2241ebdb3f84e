// Integrators by name (`tb render --integrator NAME`): each is a function that renders passes
// of a World into a Film; variants are separate entries, not flags. The top layer of lib/
// (docs/overview.md): it lists the integrators of lib/integrator and the MCMC renderers of
// lib/mcmc, so it sits above both.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

struct IntegratorParameter {
  std::string name;
  std::string description;  // with its default
};

struct IntegratorInfo {
  std::string name;
  std::string description;
  // Renders into the film; returns the number of passes (Welch samples per pixel) done.
  std::function<int64_t(const World&, const RenderSettings&, Film&)> render;
  // The RenderSettings::params it reads.
  std::vector<IntegratorParameter> parameters = {};
};

// Checks settings.params against the integrator's parameter list: empty when every name is
// known and every value finite, else a message naming the first bad parameter and the known ones.
std::string validate_params(const IntegratorInfo& info, const std::map<std::string, double>& params);

// The registered integrators, sorted by name.
const std::vector<IntegratorInfo>& integrators();
const IntegratorInfo* find_integrator(const std::string& name);

}  // namespace tb
