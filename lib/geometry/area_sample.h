// A point sampled on a surface, with its density in the AREA measure (world space).
#pragma once

#include "lib/geometry/hit.h"

namespace tb {

struct AreaSample {
  Hit hit;               // the sampled point with its full differential geometry (t = 0)
  double pdf_area = 0;   // density per unit world-space area
};

}  // namespace tb
