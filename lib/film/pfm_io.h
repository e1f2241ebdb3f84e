// Portable Float Map (PFM) input and output: the HDR format many renderers write (Tungsten's
// hdr_output_file among them). Layout:
//   "PF" (3 channels, RGB) or "Pf" (1 channel, greyscale), whitespace,
//   width and height (positive decimal integers), whitespace,
//   scale: a decimal number whose sign gives the byte order of the samples (negative: little
//   endian, positive: big endian), then exactly one whitespace character,
//   width * height * channels IEEE-754 float32 samples, rows stored bottom-to-top (the first
//   stored row is the bottom row of the image), pixels left to right, channels interleaved.
// In memory, as ExrImage, row 0 is the top row. The magnitude of the scale is not applied:
// this reader accepts |scale| = 1 only (what renderers write) and reports any other value
// rather than guessing whether it multiplies the samples. Strict: a bad header, a size that
// does not match the data (truncated or trailing bytes) or a non-finite sample is a
// std::runtime_error naming the file and the pixel.
#pragma once

#include <string>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/film/welch_image.h"

namespace tb {

struct PfmImage {
  int width = 0, height = 0;
  int channels = 3;       // 3 ("PF") or 1 ("Pf", read into r = g = b)
  std::vector<Rgb> rgb;   // row-major, row 0 at the top
};

enum class PfmByteOrder { kLittleEndian, kBigEndian };

// Writes "PF" (channels 3) or "Pf" (channels 1: the r channel; g and b must equal r). Values
// are stored as float32. Atomic (path + ".tmp", then rename); throws std::runtime_error naming
// the path when the image is malformed or cannot be written.
void write_pfm(const std::string& path, const PfmImage& image, PfmByteOrder order = PfmByteOrder::kLittleEndian);
// The file's bytes, for tests and for writers that want them in memory.
std::string encode_pfm(const PfmImage& image, PfmByteOrder order = PfmByteOrder::kLittleEndian);
PfmImage read_pfm(const std::string& path);
// From bytes; `name` is shown in errors.
PfmImage decode_pfm(const std::string& bytes, const std::string& name = "<pfm>");

// A reference given as a mean image and a per-pixel variance of that mean (the squared standard
// error, as renderers that estimate their own error write it; not the variance of the samples),
// as Welch statistics for compare_welch_images: each pixel holds `effective_count` Welch samples
// whose sample variance is variance_of_mean * effective_count, so that the t-test's standard
// error term var / count is the given variance of the mean. The count only sets the reference's
// share of the Welch-Satterthwaite degrees of freedom: at 10^6 it is negligible, i.e. the
// reference variance is treated as known. Sizes must match; a negative or non-finite value is a
// std::invalid_argument naming the pixel (row 0 at the top) and channel.
constexpr int64_t kReferenceEffectiveCount = 1000000;
WelchImage welch_from_reference(int width, int height, const std::vector<Rgb>& mean,
                                const std::vector<Rgb>& variance_of_mean,
                                int64_t effective_count = kReferenceEffectiveCount);

}  // namespace tb
