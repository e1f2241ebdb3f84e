#include "lib/integrator/integrator_registry.h"

#include <algorithm>

#include "lib/integrator/albedo_integrator.h"

namespace tb {

const std::vector<IntegratorInfo>& integrators() {
  // An explicit table, not static registrars: tb_render is a static library and self-registering
  // objects in it would be dropped by the linker when nothing references them.
  static const std::vector<IntegratorInfo> table = [] {
    std::vector<IntegratorInfo> t = {
        {"albedo", "primary-hit albedo (emitted radiance on emitters, directional albedo by one BSDF sample)",
         render_albedo},
    };
    std::sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    return t;
  }();
  return table;
}

const IntegratorInfo* find_integrator(const std::string& name) {
  for (const auto& i : integrators())
    if (i.name == name) return &i;
  return nullptr;
}

}  // namespace tb
