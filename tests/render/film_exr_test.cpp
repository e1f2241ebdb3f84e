// OpenEXR round trips (exact in float), Welch channels, PNG preview and tone mapping.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "lib/core/atomic_file.h"
#include "lib/core/rng.h"
#include "lib/film/exr_io.h"
#include "lib/film/film.h"
#include "lib/film/png_preview.h"

namespace tb {
namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("tb_film_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

TEST(FilmExr, FloatRoundTripIsExact) {
  ExrImage img;
  img.width = 13;
  img.height = 7;
  Rng rng(1);
  for (int i = 0; i < img.width * img.height; ++i)
    img.rgb.push_back(Rgb(float(rng.uniform() * 100), float(-rng.uniform()), float(rng.uniform() * 1e-6)));
  const std::string path = temp_path("rt.exr");
  write_exr(path, img, ExrPixelType::kFloat);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const ExrImage back = read_exr(path);
  ASSERT_EQ(back.width, 13);
  ASSERT_EQ(back.height, 7);
  EXPECT_EQ(back.rgb, img.rgb);
  EXPECT_FALSE(back.variance);
  EXPECT_FALSE(back.count);
  std::filesystem::remove(path);
}

TEST(FilmExr, HalfRoundTripWithinHalfPrecision) {
  ExrImage img;
  img.width = 4;
  img.height = 4;
  for (int i = 0; i < 16; ++i) img.rgb.push_back(Rgb(0.1 * i, 1.0 + i, 3.0));
  const std::string path = temp_path("half.exr");
  write_exr(path, img, ExrPixelType::kHalf);
  const ExrImage back = read_exr(path);
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.rgb[i][c], img.rgb[i][c], 1e-3 * std::max(1.0, img.rgb[i][c]));
  std::filesystem::remove(path);
}

TEST(FilmExr, WelchChannelsRoundTrip) {
  Film film(5, 3);
  Rng rng(2);
  for (int pass = 0; pass < 6; ++pass) {
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) film.add_sample({x + 0.5, y + 0.5}, Rgb(rng.uniform(), 2.0, 0.0), 0);
    film.end_pass();
  }
  const std::string path = temp_path("welch.exr");
  write_exr(path, exr_image_from_welch(film.welch()));
  const ExrImage back = read_exr(path);
  ASSERT_TRUE(back.variance && back.count);
  const WelchImage w = welch_from_exr_image(back);
  for (size_t i = 0; i < w.pixels(); ++i) {
    EXPECT_EQ(w.count[i], 6);
    EXPECT_NEAR(w.mean(i).r, film.welch().mean(i).r, 1e-7);
    EXPECT_NEAR(w.variance(i).r, film.welch().variance(i).r, 1e-6 * film.welch().variance(i).r + 1e-12);
    EXPECT_EQ(w.variance(i).g, 0.0);
  }
  std::filesystem::remove(path);
}

TEST(FilmExr, ReadingAMissingFileNamesIt) {
  try {
    read_exr("/nonexistent/tb_missing.exr");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tb_missing.exr"), std::string::npos);
  }
}

TEST(FilmPng, ToneMapping) {
  EXPECT_NEAR(srgb_encode(0.0), 0.0, 0);
  EXPECT_NEAR(srgb_encode(1.0), 1.0, 1e-12);
  EXPECT_NEAR(srgb_encode(0.18), 0.4613561295, 1e-8);
  const auto px = tone_map_srgb8({Rgb(1.0, 0.0, 2.0), Rgb(std::nan(""), 0.5, 0.25)}, 0.0);
  EXPECT_EQ(px[0], 255);
  EXPECT_EQ(px[1], 0);
  EXPECT_EQ(px[2], 255);
  EXPECT_EQ(px[3], 255);  // magenta marks non-finite
  EXPECT_EQ(px[4], 0);
  EXPECT_EQ(px[5], 255);
  const auto brighter = tone_map_srgb8({Rgb(0.25)}, 1.0);
  EXPECT_EQ(brighter[0], tone_map_srgb8({Rgb(0.5)}, 0.0)[0]);
}

TEST(FilmPng, WritesAValidPng) {
  const std::string path = temp_path("preview.png");
  std::vector<Rgb> img(6 * 4, Rgb(0.5, 0.2, 0.1));
  write_png_preview(path, 6, 4, img, 0.0);
  const std::string bytes = read_file(path);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace tb
