#include <stdexcept>
#include <string>

#include "lib/camera/camera.h"
#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"

namespace tb {

std::unique_ptr<Camera> make_camera(std::string_view name, const CameraSetup& setup) {
  if (name == "pinhole") return std::make_unique<PinholeCamera>(setup);
  if (name == "thin_lens") return std::make_unique<ThinLensCamera>(setup);
  throw std::invalid_argument("unknown camera '" + std::string(name) + "' (known: pinhole, thin_lens)");
}

}  // namespace tb
