#include "lib/film/exr_io.h"

#include <filesystem>
#include <stdexcept>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <half.h>
#include <fmt/format.h>

namespace tb {
namespace {

constexpr const char* kRgbNames[3] = {"R", "G", "B"};
constexpr const char* kVarNames[3] = {"variance.R", "variance.G", "variance.B"};
constexpr const char* kM3Names[3] = {"moment3.R", "moment3.G", "moment3.B"};

std::vector<float> plane(const std::vector<Rgb>& v, int c) {
  std::vector<float> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = static_cast<float>(v[i][c]);
  return out;
}
std::vector<half> plane_half(const std::vector<Rgb>& v, int c) {
  std::vector<half> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = half(static_cast<float>(v[i][c]));
  return out;
}

}  // namespace

ExrImage exr_image_from_welch(const WelchImage& w) {
  ExrImage e;
  e.width = w.width;
  e.height = w.height;
  e.rgb.resize(w.pixels());
  e.variance.emplace(w.pixels());
  e.count.emplace(w.pixels());
  if (w.has_third_moment()) e.moment3.emplace(w.pixels());
  for (size_t i = 0; i < w.pixels(); ++i) {
    e.rgb[i] = w.mean(i);
    (*e.variance)[i] = w.variance(i);
    (*e.count)[i] = static_cast<uint32_t>(w.count[i]);
    if (e.moment3) (*e.moment3)[i] = w.third_central_moment(i);
  }
  return e;
}

WelchImage welch_from_exr_image(const ExrImage& e) {
  WelchImage w(e.width, e.height);
  if (!e.moment3) w.sum_cu.clear();
  for (size_t i = 0; i < w.pixels(); ++i)
    w.set_from_moments(i, e.rgb[i], e.variance ? (*e.variance)[i] : Rgb(0.0), e.count ? (*e.count)[i] : 1,
                       e.moment3 ? (*e.moment3)[i] : Rgb(0.0));
  return w;
}

void write_exr(const std::string& path, const ExrImage& img, ExrPixelType rgb_type) {
  const size_t n = size_t(img.width) * size_t(img.height);
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != n)
    throw std::runtime_error(fmt::format("write_exr {}: image size does not match {}x{}", path, img.width, img.height));
  const std::string tmp = path + ".tmp";
  try {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    Imf::Header header(img.width, img.height);
    Imf::FrameBuffer fb;
    const size_t xs_f = sizeof(float), ys_f = sizeof(float) * size_t(img.width);
    const size_t xs_h = sizeof(half), ys_h = sizeof(half) * size_t(img.width);
    // Planes stay alive until writePixels returns.
    std::vector<std::vector<float>> fplanes;
    std::vector<std::vector<half>> hplanes;
    fplanes.reserve(10);
    hplanes.reserve(3);
    for (int c = 0; c < 3; ++c) {
      if (rgb_type == ExrPixelType::kHalf) {
        header.channels().insert(kRgbNames[c], Imf::Channel(Imf::HALF));
        hplanes.push_back(plane_half(img.rgb, c));
        fb.insert(kRgbNames[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(hplanes.back().data()), xs_h, ys_h));
      } else {
        header.channels().insert(kRgbNames[c], Imf::Channel(Imf::FLOAT));
        fplanes.push_back(plane(img.rgb, c));
        fb.insert(kRgbNames[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(fplanes.back().data()), xs_f, ys_f));
      }
    }
    if (img.variance) {
      if (img.variance->size() != n) throw std::runtime_error("variance plane has the wrong size");
      for (int c = 0; c < 3; ++c) {
        header.channels().insert(kVarNames[c], Imf::Channel(Imf::FLOAT));
        fplanes.push_back(plane(*img.variance, c));
        fb.insert(kVarNames[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(fplanes.back().data()), xs_f, ys_f));
      }
    }
    if (img.moment3) {
      if (img.moment3->size() != n) throw std::runtime_error("moment3 plane has the wrong size");
      for (int c = 0; c < 3; ++c) {
        header.channels().insert(kM3Names[c], Imf::Channel(Imf::FLOAT));
        fplanes.push_back(plane(*img.moment3, c));
        fb.insert(kM3Names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(fplanes.back().data()), xs_f, ys_f));
      }
    }
    std::vector<uint32_t> count;
    if (img.count) {
      if (img.count->size() != n) throw std::runtime_error("count plane has the wrong size");
      count = *img.count;
      header.channels().insert("count", Imf::Channel(Imf::UINT));
      fb.insert("count", Imf::Slice(Imf::UINT, reinterpret_cast<char*>(count.data()), sizeof(uint32_t),
                                    sizeof(uint32_t) * size_t(img.width)));
    }
    {
      Imf::OutputFile file(tmp.c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(img.height);
    }
    std::filesystem::rename(tmp, path);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(fmt::format("write_exr {}: {}", path, e.what()));
  }
}

ExrImage read_exr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    ExrImage img;
    img.width = dw.max.x - dw.min.x + 1;
    img.height = dw.max.y - dw.min.y + 1;
    const size_t n = size_t(img.width) * size_t(img.height);
    const Imf::ChannelList& ch = file.header().channels();
    const bool has_var = ch.findChannel(kVarNames[0]) && ch.findChannel(kVarNames[1]) && ch.findChannel(kVarNames[2]);
    const bool has_count = ch.findChannel("count") != nullptr;
    const bool has_m3 = ch.findChannel(kM3Names[0]) && ch.findChannel(kM3Names[1]) && ch.findChannel(kM3Names[2]);
    std::vector<std::vector<float>> planes(9, std::vector<float>(n, 0.0f));
    std::vector<uint32_t> count(has_count ? n : 0);
    // The slice base is offset so that pixel (dw.min.x, dw.min.y) lands at index 0.
    const auto base = [&](auto* data, size_t elem) {
      return reinterpret_cast<char*>(data) -
             (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * ptrdiff_t(img.width)) * ptrdiff_t(elem);
    };
    Imf::FrameBuffer fb;
    const size_t ys = sizeof(float) * size_t(img.width);
    for (int c = 0; c < 3; ++c)
      fb.insert(kRgbNames[c], Imf::Slice(Imf::FLOAT, base(planes[c].data(), sizeof(float)), sizeof(float), ys, 1, 1, 0.0));
    if (has_var)
      for (int c = 0; c < 3; ++c)
        fb.insert(kVarNames[c], Imf::Slice(Imf::FLOAT, base(planes[3 + c].data(), sizeof(float)), sizeof(float), ys));
    if (has_m3)
      for (int c = 0; c < 3; ++c)
        fb.insert(kM3Names[c], Imf::Slice(Imf::FLOAT, base(planes[6 + c].data(), sizeof(float)), sizeof(float), ys));
    if (has_count)
      fb.insert("count", Imf::Slice(Imf::UINT, base(count.data(), sizeof(uint32_t)), sizeof(uint32_t),
                                    sizeof(uint32_t) * size_t(img.width)));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    img.rgb.resize(n);
    for (size_t i = 0; i < n; ++i) img.rgb[i] = Rgb(planes[0][i], planes[1][i], planes[2][i]);
    if (has_var) {
      img.variance.emplace(n);
      for (size_t i = 0; i < n; ++i) (*img.variance)[i] = Rgb(planes[3][i], planes[4][i], planes[5][i]);
    }
    if (has_m3) {
      img.moment3.emplace(n);
      for (size_t i = 0; i < n; ++i) (*img.moment3)[i] = Rgb(planes[6][i], planes[7][i], planes[8][i]);
    }
    if (has_count) img.count = std::move(count);
    return img;
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("read_exr {}: {}", path, e.what()));
  }
}

}  // namespace tb
