#include "pipelines/image.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../test_util.hpp"
#include "jpeg_quality.hpp"

namespace scatter {
namespace {

Image ramp() {
  Image im(5, 3);
  for (size_t i = 0; i < im.rgb.size(); ++i) im.rgb[i] = 0.1f * float(i) + 1e-3f;
  return im;
}

TEST(ImageIo, ExrKeepsLinearFloatsExactly) {
  auto dir = test::scratch_dir("image_exr");
  Image a = ramp();
  a.rgb[4] = 1234.5f;  // beyond display range
  write_image(a, dir / "a.exr");
  Image b = read_image(dir / "a.exr");
  EXPECT_EQ(b.width, 5);
  EXPECT_EQ(b.height, 3);
  EXPECT_EQ(a.rgb, b.rgb);
}

TEST(ImageIo, PngHoldsToneMappedSrgb) {
  auto dir = test::scratch_dir("image_png");
  Image a(2, 1);
  a.rgb = {0.5f, 0.0f, 1.0f, 2.0f, 0.0031308f, 0.25f};
  write_image(a, dir / "a.png", ToneMap{1.0});
  auto in = OIIO::ImageInput::open((dir / "a.png").string());
  ASSERT_TRUE(in);
  std::vector<unsigned char> px(6);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data()));
  // sRGB(0.5) = 0.7354 -> 188; 1 and above clamp to 255; 0.0031308 -> 0.04045 -> 10; 0.25 -> 137.
  EXPECT_EQ(px, (std::vector<unsigned char>{188, 0, 255, 255, 10, 137}));
  write_image(a, dir / "b.png", ToneMap{0.5});
  EXPECT_EQ(to_srgb8(a, ToneMap{0.5})[3], 255);  // 2.0 * 0.5 = 1
  EXPECT_EQ(to_srgb8(a, ToneMap{0.5})[0], 137);  // 0.25
}

TEST(ImageIo, SrgbBytesAreTheFormulaRounded) {
  // Every step of the 8-bit curve, and values on both sides of each, against the sRGB formula.
  Image image(1, 1);
  image.rgb.clear();
  for (int i = 0; i <= 200000; ++i) image.rgb.push_back(float(i) / 160000);  // 0 .. 1.25
  image.rgb.insert(image.rgb.end(), {-1.f, std::nanf(""), 1e30f});
  image.width = 1;
  image.height = int(image.rgb.size());  // rgb is 3 floats a pixel: pad to a whole pixel count
  while (image.rgb.size() % 3) image.rgb.push_back(0.5f);
  image.height = int(image.rgb.size() / 3);
  std::vector<unsigned char> bytes = to_srgb8(image, ToneMap{1.0});
  for (size_t i = 0; i < 200001; ++i) {
    double v = std::clamp(double(image.rgb[i]), 0.0, 1.0);
    double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    ASSERT_EQ(int(bytes[i]), int(std::lround(s * 255))) << "linear " << image.rgb[i];
  }
  EXPECT_EQ(bytes[200001], 0);    // negative
  EXPECT_EQ(bytes[200002], 0);    // NaN: black, not white
  EXPECT_EQ(bytes[200003], 255);  // huge
}

TEST(ImageIo, UnknownExtensionAndUnwritablePathsAreErrors) {
  auto dir = test::scratch_dir("image_errors");
  EXPECT_THROW(write_image(ramp(), dir / "a.bmpx"), std::runtime_error);
  EXPECT_THROW(write_image(ramp(), dir / "no" / "such" / "dir.png"), std::runtime_error);
  write_image(ramp(), dir / "a.jpg");
  EXPECT_TRUE(std::filesystem::file_size(dir / "a.jpg") > 0);
}

// Noise: the worst case for JPEG, so that quality shows in the size.
Image noise(int w, int h) {
  Image im(w, h);
  unsigned x = 12345;
  for (float& v : im.rgb) v = float((x = x * 1664525u + 1013904223u) >> 8) / float(1 << 24);
  return im;
}

TEST(ImageIo, JpegIsEncodedAtTheAskedQuality) {
  Image im = noise(64, 64);
  std::string low = encode_image(im, "jpg", {}, kMovingJpegQuality);
  std::string high = encode_image(im, "jpg", {}, kJpegQuality);
  EXPECT_EQ(test::jpeg_quality(low), kMovingJpegQuality);
  EXPECT_EQ(test::jpeg_quality(high), kJpegQuality);
  EXPECT_EQ(test::jpeg_quality(encode_image(im, "jpg")), kJpegQuality);  // the default
  EXPECT_EQ(test::jpeg_quality(encode_image(im, "jpg", {}, 20)), 20);
  EXPECT_LT(low.size(), high.size());
  EXPECT_THROW(encode_image(im, "jpg", {}, 0), std::invalid_argument);
  EXPECT_THROW(encode_image(im, "jpg", {}, 101), std::invalid_argument);
  EXPECT_EQ(encode_image(im, "png", {}, 50), encode_image(im, "png"));  // PNG ignores it
}

}  // namespace
}  // namespace scatter
