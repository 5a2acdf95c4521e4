// Linear float RGB images, and writing them: EXR keeps linear radiance (OpenImageIO); PNG and JPEG
// hold tone-mapped sRGB (libpng, OpenImageIO).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace scatter {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // 3 floats per pixel, row 0 at the top

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(size_t(w) * h * 3, 0.f) {}
  Vec3 at(int x, int y) const {
    const float* p = &rgb[(size_t(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
  }
};

struct ToneMap {
  double exposure = 1.0;  // radiance is multiplied by this, clamped to [0, 1], then sRGB encoded
};

// `image` resampled to width x height, bilinear between pixel centres (edges clamped): for a
// smooth term rendered at a fraction of the size.
Image resample(const Image& image, int width, int height);

// Encodes linear radiance as 8-bit sRGB, 3 bytes per pixel.
std::vector<unsigned char> to_srgb8(const Image& image, const ToneMap& tone = {});
// Throws std::runtime_error unless `path` has an extension write_image() knows.
void check_image_path(const std::filesystem::path& path);
// JPEG quality on libjpeg's 1-100 scale where none is asked for: a still frame's (trame's choice
// for a still view; a live session's frames while the user drags take kMovingJpegQuality).
constexpr int kJpegQuality = 90, kMovingJpegQuality = 50;
// Encodes into memory: "exr" (linear float), "png" (libpng), "jpg" (OpenImageIO, at
// `jpeg_quality`, 1-100; the other formats ignore it). Throws std::invalid_argument for a
// quality outside 1-100.
std::string encode_image(const Image& image, const std::string& format, const ToneMap& tone = {},
                         int jpeg_quality = kJpegQuality);
// Writes by extension: .exr (linear float), .png (libpng), .jpg/.jpeg (OpenImageIO).
// Throws std::runtime_error naming the file on failure or an unknown extension.
void write_image(const Image& image, const std::filesystem::path& path, const ToneMap& tone = {});
// Reads an EXR (or any format OpenImageIO reads) as linear float RGB.
Image read_image(const std::filesystem::path& path);

}  // namespace scatter
