// Tone-mapped 8-bit PNG previews (libpng): scale by 2^exposure_stops, clamp to [0, 1], encode
// with the sRGB transfer function (IEC 61966-2-1), round to 8 bits. Pixels with a non-finite channel are
// written magenta so they are seen, not hidden. Written atomically (write_file_atomic).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"

namespace tb {

// Linear value -> sRGB-encoded value in [0, 1].
double srgb_encode(double linear);
// Row-major 8-bit RGB after tone mapping.
std::vector<uint8_t> tone_map_srgb8(const std::vector<Rgb>& rgb, double exposure_stops);
// Throws std::runtime_error naming the path on failure.
void write_png_preview(const std::string& path, int width, int height, const std::vector<Rgb>& rgb,
                       double exposure_stops = 0.0);

}  // namespace tb
