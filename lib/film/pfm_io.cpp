#include "lib/film/pfm_io.h"

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"

namespace tb {

namespace {

constexpr bool kHostLittle = std::endian::native == std::endian::little;

uint32_t swap32(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

void put_float(std::string& out, float f, bool little) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  if (little != kHostLittle) u = swap32(u);
  char b[4];
  std::memcpy(b, &u, 4);
  out.append(b, 4);
}

float get_float(const char* p, bool little) {
  uint32_t u;
  std::memcpy(&u, p, 4);
  if (little != kHostLittle) u = swap32(u);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw std::runtime_error(fmt::format("{}: PFM: {}", name, what));
}

// The next whitespace-delimited header token starting at pos (skipping leading whitespace).
std::string token(const std::string& bytes, size_t& pos, const std::string& name, const char* what) {
  while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
  const size_t start = pos;
  while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
  if (start == pos) fail(name, fmt::format("header ends before the {}", what));
  return bytes.substr(start, pos - start);
}

int parse_size(const std::string& t, const std::string& name, const char* what) {
  if (t.empty() || t.size() > 9) fail(name, fmt::format("{} '{}' is not a positive integer below 10^9", what, t));
  for (char c : t)
    if (!std::isdigit(static_cast<unsigned char>(c)))
      fail(name, fmt::format("{} '{}' is not a positive integer", what, t));
  const int v = std::stoi(t);
  if (v < 1) fail(name, fmt::format("{} must be positive, is {}", what, v));
  return v;
}

}  // namespace

std::string encode_pfm(const PfmImage& img, PfmByteOrder order) {
  if (img.width < 1 || img.height < 1) throw std::runtime_error("PFM: width and height must be positive");
  if (img.channels != 1 && img.channels != 3) throw std::runtime_error("PFM: channels must be 1 or 3");
  if (img.rgb.size() != size_t(img.width) * size_t(img.height))
    throw std::runtime_error(fmt::format("PFM: {} pixels for a {} x {} image", img.rgb.size(), img.width, img.height));
  const bool little = order == PfmByteOrder::kLittleEndian;
  std::string out = fmt::format("{}\n{} {}\n{}\n", img.channels == 3 ? "PF" : "Pf", img.width, img.height,
                                little ? "-1.0" : "1.0");
  out.reserve(out.size() + img.rgb.size() * size_t(img.channels) * 4);
  for (int y = img.height - 1; y >= 0; --y)  // bottom row first
    for (int x = 0; x < img.width; ++x) {
      const Rgb& v = img.rgb[size_t(y) * size_t(img.width) + size_t(x)];
      if (img.channels == 1 && (v.g != v.r || v.b != v.r))
        throw std::runtime_error(fmt::format("PFM: pixel ({}, {}) is not grey in a 1-channel image", x, y));
      for (int c = 0; c < img.channels; ++c) {
        if (!std::isfinite(v[c]) || std::abs(v[c]) > double(std::numeric_limits<float>::max()))
          throw std::runtime_error(fmt::format("PFM: pixel ({}, {}) channel {} = {} is not a finite float", x, y, c, v[c]));
        put_float(out, static_cast<float>(v[c]), little);
      }
    }
  return out;
}

void write_pfm(const std::string& path, const PfmImage& image, PfmByteOrder order) {
  std::string bytes;
  try {
    bytes = encode_pfm(image, order);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("{}: {}", path, e.what()));
  }
  write_file_atomic(path, bytes);
}

PfmImage decode_pfm(const std::string& bytes, const std::string& name) {
  size_t pos = 0;
  PfmImage img;
  const std::string magic = token(bytes, pos, name, "magic number");
  if (magic == "PF")
    img.channels = 3;
  else if (magic == "Pf")
    img.channels = 1;
  else
    fail(name, fmt::format("magic number '{}' is neither PF (RGB) nor Pf (greyscale)", magic.substr(0, 16)));
  img.width = parse_size(token(bytes, pos, name, "width"), name, "width");
  img.height = parse_size(token(bytes, pos, name, "height"), name, "height");
  const std::string st = token(bytes, pos, name, "scale");
  double scale = 0;
  try {
    size_t used = 0;
    scale = std::stod(st, &used);
    if (used != st.size()) throw std::invalid_argument(st);
  } catch (const std::exception&) {
    fail(name, fmt::format("scale '{}' is not a number", st.substr(0, 32)));
  }
  if (!std::isfinite(scale) || scale == 0) fail(name, fmt::format("scale '{}' must be finite and non-zero", st));
  if (std::abs(scale) != 1.0)
    fail(name, fmt::format("scale {} has magnitude other than 1; whether it multiplies the samples is not "
                           "standardised, so it is not applied and the file is not read",
                           st));
  const bool little = scale < 0;
  if (pos >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[pos])))
    fail(name, "no whitespace character after the scale");
  ++pos;  // exactly one whitespace character before the samples
  const size_t n = size_t(img.width) * size_t(img.height) * size_t(img.channels);
  const size_t have = bytes.size() - pos;
  if (have != 4 * n)
    fail(name, fmt::format("{} x {} x {} float32 samples need {} bytes after the header, the file has {} ({})",
                           img.width, img.height, img.channels, 4 * n, have, have < 4 * n ? "truncated" : "trailing data"));
  img.rgb.assign(size_t(img.width) * size_t(img.height), Rgb(0.0));
  const char* p = bytes.data() + pos;
  for (int row = 0; row < img.height; ++row) {
    const int y = img.height - 1 - row;  // stored bottom-to-top
    for (int x = 0; x < img.width; ++x) {
      Rgb& v = img.rgb[size_t(y) * size_t(img.width) + size_t(x)];
      for (int c = 0; c < img.channels; ++c, p += 4) {
        const float f = get_float(p, little);
        if (!std::isfinite(f))
          fail(name, fmt::format("pixel ({}, {}) (row 0 at the top) channel {} is not finite", x, y, c));
        v[c] = f;
      }
      if (img.channels == 1) v = Rgb(v.r);
    }
  }
  return img;
}

PfmImage read_pfm(const std::string& path) { return decode_pfm(read_file(path), path); }

WelchImage welch_from_reference(int width, int height, const std::vector<Rgb>& mean,
                                const std::vector<Rgb>& variance_of_mean, int64_t effective_count) {
  if (width < 1 || height < 1) throw std::invalid_argument("reference: width and height must be positive");
  const size_t n = size_t(width) * size_t(height);
  if (mean.size() != n || variance_of_mean.size() != n)
    throw std::invalid_argument(fmt::format("reference: {} x {} pixels expected, the mean has {}, the variance {}",
                                            width, height, mean.size(), variance_of_mean.size()));
  if (effective_count < 2) throw std::invalid_argument("reference: the effective sample count must be at least 2");
  WelchImage w(width, height);
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      const int x = int(i % size_t(width)), y = int(i / size_t(width));
      if (!std::isfinite(mean[i][c]))
        throw std::invalid_argument(fmt::format("reference mean: pixel ({}, {}) channel {} is not finite", x, y, c));
      if (!std::isfinite(variance_of_mean[i][c]) || variance_of_mean[i][c] < 0)
        throw std::invalid_argument(fmt::format("reference variance: pixel ({}, {}) channel {} = {} is not a finite "
                                                "non-negative number",
                                                x, y, c, variance_of_mean[i][c]));
    }
    w.set_from_moments(i, mean[i], variance_of_mean[i] * double(effective_count), effective_count);
  }
  return w;
}

}  // namespace tb
