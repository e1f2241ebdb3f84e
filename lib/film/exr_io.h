// OpenEXR 3 output and input (Imf::OutputFile / Imf::InputFile with an explicit FrameBuffer, so
// that channels beyond RGBA can be written). Channels:
//   R, G, B                      the image (HALF or FLOAT),
//   variance.R/G/B (optional)    the unbiased sample variance of the per-pixel Welch samples (FLOAT),
//   count (optional)             the number of Welch samples per pixel (UINT),
//   moment3.R/G/B (optional)     the third central moment (1/n) sum (x - mean)^3 of the Welch
//                                samples (FLOAT), for the skew-corrected comparison.
// Mean, variance and count rebuild the Welch sums exactly enough to use a stored image as a
// reference in a Welch t-test (sums of squares in float would cancel catastrophically).
// Writes are atomic: path + ".tmp", then std::filesystem::rename.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/film/welch_image.h"

namespace tb {

enum class ExrPixelType { kHalf, kFloat };

struct ExrImage {
  int width = 0, height = 0;
  std::vector<Rgb> rgb;                          // row-major, row 0 at the top
  std::optional<std::vector<Rgb>> variance;      // of the Welch samples
  std::optional<std::vector<uint32_t>> count;    // Welch samples per pixel
  std::optional<std::vector<Rgb>> moment3;       // third central moment of the Welch samples
};

// From a Welch image: mean, variance of the Welch samples, count, and the third central moment
// when the image has it.
ExrImage exr_image_from_welch(const WelchImage& w);
// Back to Welch sums; without variance/count channels every pixel gets count 1, variance 0;
// without moment3 the image has no third moment (WelchImage::has_third_moment() false).
WelchImage welch_from_exr_image(const ExrImage& e);

// Throws std::runtime_error naming the path when the file cannot be written.
void write_exr(const std::string& path, const ExrImage& image, ExrPixelType rgb_type = ExrPixelType::kFloat);
// Reads R, G, B (missing channels read as 0) and, when present, variance.* and count.
ExrImage read_exr(const std::string& path);

}  // namespace tb
