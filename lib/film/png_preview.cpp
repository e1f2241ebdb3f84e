#include "lib/film/png_preview.h"

#include <csetjmp>
#include <stdexcept>

#include <fmt/format.h>
#include <png.h>

#include "lib/core/atomic_file.h"

namespace tb {

double srgb_encode(double v) {
  // IEC 61966-2-1: linear segment below 0.0031308, power 1/2.4 above.
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

std::vector<uint8_t> tone_map_srgb8(const std::vector<Rgb>& rgb, double exposure_stops) {
  const double scale = std::exp2(exposure_stops);
  std::vector<uint8_t> out(rgb.size() * 3);
  for (size_t i = 0; i < rgb.size(); ++i) {
    const Rgb v = rgb[i] * scale;
    const bool bad = !is_finite(v);
    for (int c = 0; c < 3; ++c) {
      const double e = bad ? (c == 1 ? 0.0 : 1.0) : srgb_encode(std::clamp(v[c], 0.0, 1.0));  // magenta if bad
      out[3 * i + size_t(c)] = static_cast<uint8_t>(std::lround(255.0 * e));
    }
  }
  return out;
}

namespace {
void append_to_string(png_structp png, png_bytep data, png_size_t length) {
  auto* s = static_cast<std::string*>(png_get_io_ptr(png));
  s->append(reinterpret_cast<const char*>(data), length);
}
void no_flush(png_structp) {}
}  // namespace

void write_png_preview(const std::string& path, int width, int height, const std::vector<Rgb>& rgb,
                       double exposure_stops) {
  if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height))
    throw std::runtime_error(fmt::format("write_png_preview {}: size does not match {}x{}", path, width, height));
  const std::vector<uint8_t> pixels = tone_map_srgb8(rgb, exposure_stops);
  std::string encoded;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error("write_png_preview: png_create_write_struct failed");
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error(fmt::format("write_png_preview {}: libpng error", path));
  }
  png_set_write_fn(png, &encoded, append_to_string, no_flush);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y)
    png_write_row(png, const_cast<png_bytep>(pixels.data() + size_t(y) * size_t(width) * 3));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  write_file_atomic(path, encoded);
}

}  // namespace tb
