// Portable Float Map input and output (lib/film/pfm_io.h): round trips in both byte orders and
// both channel counts, the stored row order (bottom row first) and byte order checked on the raw
// bytes, hand-written files of other writers, and every malformed header or size an error.
// The reference form (welch_from_reference: a mean and a variance-of-the-mean image): the t
// statistic it gives, and a statistical check on synthetic Gaussian images (alpha = 0.01, fixed
// seed) with two negative controls that must be rejected: a 2% scaled reference mean, and the
// same noisy reference with its variance left out.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "lib/core/atomic_file.h"
#include "lib/core/rng.h"
#include "lib/film/pfm_io.h"
#include "validate/image_compare.h"

namespace tb {
namespace {

PfmImage ramp(int w, int h) {
  PfmImage img;
  img.width = w;
  img.height = h;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.rgb.push_back(Rgb(x + 10.0 * y, 0.5 + y, -0.25 * x) * 0.125);  // exact in float
  return img;
}

float raw_float(const std::string& bytes, size_t offset, bool little) {
  unsigned char b[4];
  std::memcpy(b, bytes.data() + offset, 4);
  uint32_t u = little ? (uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24)
                      : (uint32_t(b[3]) | uint32_t(b[2]) << 8 | uint32_t(b[1]) << 16 | uint32_t(b[0]) << 24);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

std::string error_of(const std::string& bytes) {
  try {
    decode_pfm(bytes, "x.pfm");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PfmIo, RoundTripsInBothByteOrders) {
  const PfmImage img = ramp(5, 3);
  for (PfmByteOrder order : {PfmByteOrder::kLittleEndian, PfmByteOrder::kBigEndian}) {
    const std::string bytes = encode_pfm(img, order);
    const bool little = order == PfmByteOrder::kLittleEndian;
    const std::string header = little ? "PF\n5 3\n-1.0\n" : "PF\n5 3\n1.0\n";
    ASSERT_EQ(bytes.substr(0, header.size()), header);
    ASSERT_EQ(bytes.size(), header.size() + 5 * 3 * 3 * 4);
    // The first stored pixel is the bottom-left one (row 2), the last the top-right (row 0).
    EXPECT_EQ(raw_float(bytes, header.size(), little), float(img.rgb[2 * 5].r));
    EXPECT_EQ(raw_float(bytes, header.size() + 4, little), float(img.rgb[2 * 5].g));
    EXPECT_EQ(raw_float(bytes, bytes.size() - 4, little), float(img.rgb[4].b));
    const PfmImage back = decode_pfm(bytes);
    EXPECT_EQ(back.width, 5);
    EXPECT_EQ(back.height, 3);
    EXPECT_EQ(back.channels, 3);
    ASSERT_EQ(back.rgb.size(), img.rgb.size());
    for (size_t i = 0; i < img.rgb.size(); ++i) EXPECT_EQ(back.rgb[i], img.rgb[i]) << i;
  }
}

TEST(PfmIo, FileRoundTripAndGreyscale) {
  const std::string dir = (std::filesystem::temp_directory_path() / "tb_pfm_io_test").string();
  std::filesystem::create_directories(dir);
  PfmImage grey;
  grey.width = 2;
  grey.height = 2;
  grey.channels = 1;
  grey.rgb = {Rgb(1.0), Rgb(2.0), Rgb(3.0), Rgb(4.5)};
  write_pfm(dir + "/g.pfm", grey, PfmByteOrder::kBigEndian);
  const std::string bytes = read_file(dir + "/g.pfm");
  EXPECT_EQ(bytes.substr(0, 11), "Pf\n2 2\n1.0\n");
  EXPECT_EQ(bytes.size(), 11u + 4 * 4);
  EXPECT_EQ(raw_float(bytes, 11, false), 3.0f);  // bottom-left first
  const PfmImage back = read_pfm(dir + "/g.pfm");
  EXPECT_EQ(back.channels, 1);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(back.rgb[i], grey.rgb[i]);
  grey.rgb[1] = Rgb(2.0, 2.0, 2.5);  // not grey: cannot be written as Pf
  EXPECT_THROW(write_pfm(dir + "/g2.pfm", grey), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(PfmIo, ReadsOtherWritersHeaders) {
  // One space-separated header line, CRLF-free but with extra blanks, big endian 1 x 2 RGB.
  std::string bytes = "PF 1   2 1\n";
  const float v[6] = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f};  // bottom pixel, then top pixel
  for (float f : v) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    for (int s = 24; s >= 0; s -= 8) bytes.push_back(char((u >> s) & 0xff));
  }
  const PfmImage img = decode_pfm(bytes);
  ASSERT_EQ(img.width, 1);
  ASSERT_EQ(img.height, 2);
  EXPECT_EQ(img.rgb[0], Rgb(4, 5, 6));  // top
  EXPECT_EQ(img.rgb[1], Rgb(1, 2, 3));  // bottom
}

TEST(PfmIo, MalformedFilesAreErrorsSayingWhat) {
  const std::string good = encode_pfm(ramp(2, 2));
  EXPECT_NE(error_of("P6\n2 2\n255\n").find("neither PF"), std::string::npos);
  EXPECT_NE(error_of("PF\n0 2\n-1.0\n").find("width must be positive"), std::string::npos);
  EXPECT_NE(error_of("PF\n2 -2\n-1.0\n").find("height '-2' is not a positive integer"), std::string::npos);
  EXPECT_NE(error_of("PF\n2 2\n0\n").find("finite and non-zero"), std::string::npos);
  EXPECT_NE(error_of("PF\n2 2\nabc\n").find("is not a number"), std::string::npos);
  EXPECT_NE(error_of("PF\n2 2\n-2.0\n" + std::string(48, '\0')).find("magnitude other than 1"), std::string::npos);
  EXPECT_NE(error_of("PF\n2 2").find("header ends before the scale"), std::string::npos);
  EXPECT_NE(error_of(good.substr(0, good.size() - 1)).find("truncated"), std::string::npos);
  EXPECT_NE(error_of(good + "x").find("trailing data"), std::string::npos);
  std::string nan = good;
  const char q[4] = {0, 0, char(0xc0), 0x7f};  // a quiet NaN, little endian as the file
  std::memcpy(&nan[nan.size() - 4], q, 4);      // top-right pixel, blue
  const std::string e = error_of(nan);
  EXPECT_NE(e.find("x.pfm: PFM: pixel (1, 0) (row 0 at the top) channel 2 is not finite"), std::string::npos) << e;
  EXPECT_THROW(read_pfm((std::filesystem::temp_directory_path() / "tb_pfm_io_test_missing.pfm").string()),
               std::runtime_error);
  PfmImage inf = ramp(1, 1);
  inf.rgb[0].g = 1e300;  // not representable as float
  EXPECT_THROW(encode_pfm(inf), std::runtime_error);
}

double gaussian(Rng& r) {
  const double u1 = 1.0 - r.uniform(), u2 = r.uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

TEST(PfmReference, TheTStatisticUsesTheGivenVarianceOfTheMean) {
  WelchImage a(1, 1);
  for (double v : {1.0, 2.0, 4.0, 3.0, 0.5, 2.5, 1.5, 3.5}) a.add(0, Rgb(v, 2.0 * v, v + 1.0));
  const double mean_a = 18.0 / 8.0;
  double ss = 0;
  for (double v : {1.0, 2.0, 4.0, 3.0, 0.5, 2.5, 1.5, 3.5}) ss += (v - mean_a) * (v - mean_a);
  const double var_a = ss / 7.0;
  const double m = 1.7, vm = 0.03;  // reference mean and variance of the mean, channel R
  const WelchImage ref = welch_from_reference(1, 1, {Rgb(m, 2.0 * m, m + 1.0)}, {Rgb(vm, 4.0 * vm, vm)});
  EXPECT_EQ(ref.count[0], kReferenceEffectiveCount);
  EXPECT_NEAR(ref.variance(0).r / double(ref.count[0]), vm, 1e-12);
  EXPECT_NEAR(ref.mean(0).g, 2.0 * m, 1e-12);
  const ImageCompareResult r = compare_welch_images(a, ref, 0.01);
  const double t = (mean_a - m) / std::sqrt(var_a / 8.0 + vm);  // the same in every channel
  EXPECT_NEAR(r.worst.t, t, 1e-6 * std::abs(t));
  // Welch-Satterthwaite: the reference's share is negligible at 10^6, the dof is A's 7 inflated
  // by the known reference variance.
  const double sa = var_a / 8.0;
  const double dof = (sa + vm) * (sa + vm) / (sa * sa / 7.0 + vm * vm / double(kReferenceEffectiveCount - 1));
  EXPECT_NEAR(r.worst.dof, dof, 1e-6 * dof);
}

TEST(PfmReference, NoisyReferenceWithItsVarianceIsConsistentAndBiasesAreRejected) {
  constexpr int kW = 32, kH = 32, kN = 16;
  constexpr double kAlpha = 0.01;
  Rng rng(20261202);
  WelchImage a(kW, kH);
  std::vector<Rgb> ref_mean(kW * kH), ref_var(kW * kH), truth(kW * kH);
  for (size_t i = 0; i < truth.size(); ++i) {
    truth[i] = Rgb(1.0 + 0.01 * double(i % 97), 0.5 + 0.002 * double(i % 31), 2.0);
    const double sigma_a = 0.3 * truth[i].r;  // per Welch sample of A
    for (int k = 0; k < kN; ++k)
      a.add(i, truth[i] + sigma_a * Rgb(gaussian(rng), gaussian(rng), gaussian(rng)));
    // The reference's own error, 2x A's standard error: not negligible.
    const double sd_ref = 2.0 * sigma_a / std::sqrt(double(kN));
    ref_var[i] = Rgb(sd_ref * sd_ref);
    ref_mean[i] = truth[i] + sd_ref * Rgb(gaussian(rng), gaussian(rng), gaussian(rng));
  }
  const ImageCompareResult same = compare_welch_images(a, welch_from_reference(kW, kH, ref_mean, ref_var), kAlpha);
  EXPECT_FALSE(same.rejects()) << same.message();
  std::vector<Rgb> scaled = ref_mean;
  for (Rgb& v : scaled) v *= 1.02;
  const ImageCompareResult biased = compare_welch_images(a, welch_from_reference(kW, kH, scaled, ref_var), kAlpha);
  EXPECT_TRUE(biased.rejects()) << biased.message();
  const std::vector<Rgb> zero(kW * kH, Rgb(0.0));
  const ImageCompareResult no_var = compare_welch_images(a, welch_from_reference(kW, kH, ref_mean, zero), kAlpha);
  EXPECT_TRUE(no_var.rejects()) << no_var.message();
  std::cout << "reference with variance: p = " << same.p_value() << "; mean x 1.02: p = " << biased.p_value()
            << "; variance left out: p = " << no_var.p_value() << "\n";
}

TEST(PfmReference, BadReferencesAreErrors) {
  const std::vector<Rgb> one(4, Rgb(1.0));
  std::vector<Rgb> neg = one;
  neg[3].b = -1e-3;
  try {
    welch_from_reference(2, 2, one, neg);
    ADD_FAILURE() << "negative variance accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("reference variance: pixel (1, 1) channel 2"), std::string::npos) << e.what();
  }
  std::vector<Rgb> nan = one;
  nan[1].g = std::nan("");
  EXPECT_THROW(welch_from_reference(2, 2, nan, one), std::invalid_argument);
  EXPECT_THROW(welch_from_reference(2, 2, one, nan), std::invalid_argument);
  EXPECT_THROW(welch_from_reference(2, 2, one, std::vector<Rgb>(3, Rgb(0.0))), std::invalid_argument);
  EXPECT_THROW(welch_from_reference(2, 2, one, one, 1), std::invalid_argument);
}

}  // namespace
}  // namespace tb
