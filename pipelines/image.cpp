#include "pipelines/image.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <tuple>

namespace scatter {
namespace {

unsigned char encode_srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
  return static_cast<unsigned char>(std::lround(s * 255));
}

// The linear value at which encode_srgb() steps from k to k + 1, for k = 0..254 (and a 256th
// step above 1 that is never reached).
const std::array<double, 256>& srgb_steps() {
  static const std::array<double, 256> steps = [] {
    std::array<double, 256> t{};
    t[255] = 2.0;
    for (int k = 0; k < 255; ++k) {
      double s = (k + 0.5) / 255;  // the sRGB value that rounds up to k + 1
      double v = s <= 12.92 * 0.0031308 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
      // Nudge onto the exact step of encode_srgb (the formula's inverse is off by an ulp or so).
      while (encode_srgb(v) > k) v = std::nextafter(v, 0.0);
      while (encode_srgb(v) <= k) v = std::nextafter(v, 2.0);
      t[k] = v;
    }
    return t;
  }();
  return steps;
}

// to_srgb8 without pow(): the byte at the start of each of kBuckets equal slices of [0, 1], then
// one comparison with the next step (the curve rises less than one level per slice: its steepest
// slope, 12.92 x 255 near black, is 0.8 levels a slice). Gives exactly encode_srgb's bytes.
constexpr int kBuckets = 4096;
const std::array<unsigned char, kBuckets + 1>& srgb_buckets() {
  static const std::array<unsigned char, kBuckets + 1> b = [] {
    std::array<unsigned char, kBuckets + 1> t{};
    for (int i = 0; i <= kBuckets; ++i) t[i] = encode_srgb(double(i) / kBuckets);
    return t;
  }();
  return b;
}

void append_bytes(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::string*>(png_get_io_ptr(png));
  out->append(reinterpret_cast<const char*>(data), n);
}

std::string encode_png(const Image& image, const ToneMap& tone) {
  std::vector<unsigned char> bytes = to_srgb8(image, tone);
  std::string out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error("libpng cannot start encoding");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng failed encoding a PNG");
  }
  png_set_write_fn(png, &out, append_bytes, nullptr);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) png_write_row(png, &bytes[size_t(y) * image.width * 3]);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

// EXR (linear float) and JPEG (sRGB) through OpenImageIO, into memory.
std::string encode_oiio(const Image& image, const std::string& format, const ToneMap& tone,
                        int jpeg_quality) {
  const bool linear = format == "exr";
  std::vector<unsigned char> buffer;
  OIIO::Filesystem::IOVecOutput proxy(buffer);
  std::string name = "image." + format;
  auto out = OIIO::ImageOutput::create(name);
  if (!out || !out->set_ioproxy(&proxy))
    throw std::runtime_error("OpenImageIO cannot encode " + format + ": " + OIIO::geterror());
  OIIO::ImageSpec spec(image.width, image.height, 3,
                       linear ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  if (!linear) spec.attribute("Compression", "jpeg:" + std::to_string(jpeg_quality));
  bool ok = out->open(name, spec);
  if (ok && linear) {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data());
  } else if (ok) {
    std::vector<unsigned char> bytes = to_srgb8(image, tone);
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  if (!ok || !out->close())
    throw std::runtime_error("cannot encode " + format + ": " + out->geterror());
  return std::string(buffer.begin(), buffer.end());
}

}  // namespace

Image resample(const Image& image, int width, int height) {
  Image out(width, height);
  if (image.width <= 0 || image.height <= 0) return out;
  // Pixel (x, y) of the output samples the source at its centre's position in source pixels.
  auto axis = [](int i, int n, int source) {
    double u = std::clamp((i + 0.5) * source / n - 0.5, 0.0, source - 1.0);
    int i0 = std::min(static_cast<int>(u), source - 1);
    return std::tuple{i0, std::min(i0 + 1, source - 1), u - i0};
  };
  for (int y = 0; y < height; ++y) {
    auto [y0, y1, fy] = axis(y, height, image.height);
    for (int x = 0; x < width; ++x) {
      auto [x0, x1, fx] = axis(x, width, image.width);
      for (int c = 0; c < 3; ++c) {
        auto at = [&](int px, int py) {
          return image.rgb[(size_t(py) * image.width + px) * 3 + c];
        };
        double top = at(x0, y0) * (1 - fx) + at(x1, y0) * fx;
        double bottom = at(x0, y1) * (1 - fx) + at(x1, y1) * fx;
        out.rgb[(size_t(y) * width + x) * 3 + c] = static_cast<float>(top * (1 - fy) + bottom * fy);
      }
    }
  }
  return out;
}

std::vector<unsigned char> to_srgb8(const Image& image, const ToneMap& tone) {
  const auto& steps = srgb_steps();
  const auto& buckets = srgb_buckets();
  std::vector<unsigned char> bytes(image.rgb.size());
  for (size_t i = 0; i < bytes.size(); ++i) {
    double v = double(image.rgb[i]) * tone.exposure;
    if (!(v > 0)) v = 0;  // NaN too
    if (v >= 1) v = 1;
    unsigned k = buckets[static_cast<int>(v * kBuckets)];
    bytes[i] = static_cast<unsigned char>(k + (v >= steps[k]));
  }
  return bytes;
}

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

void check_image_path(const std::filesystem::path& path) {
  std::string ext = lower_extension(path);
  if (ext != ".png" && ext != ".exr" && ext != ".jpg" && ext != ".jpeg")
    throw std::runtime_error("cannot write " + path.string() +
                             ": unknown image type (use .exr, .png or .jpg)");
}

std::string encode_image(const Image& image, const std::string& format, const ToneMap& tone,
                         int jpeg_quality) {
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw std::invalid_argument("JPEG quality " + std::to_string(jpeg_quality) +
                                " is outside 1-100");
  if (format == "png") return encode_png(image, tone);
  if (format == "exr" || format == "jpg" || format == "jpeg")
    return encode_oiio(image, format, tone, jpeg_quality);
  throw std::runtime_error("unknown image format \"" + format + "\" (use exr, png or jpg)");
}

void write_image(const Image& image, const std::filesystem::path& path, const ToneMap& tone) {
  check_image_path(path);
  std::string bytes = encode_image(image, lower_extension(path).substr(1), tone);
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}

Image read_image(const std::filesystem::path& path) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) throw std::runtime_error("cannot read " + path.string() + ": " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.nchannels < 3) throw std::runtime_error(path.string() + " has fewer than 3 channels");
  Image image(spec.width, spec.height);
  std::vector<float> all(size_t(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
    throw std::runtime_error("cannot read " + path.string() + ": " + in->geterror());
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p)
    for (int c = 0; c < 3; ++c) image.rgb[3 * p + c] = all[p * spec.nchannels + c];
  return image;
}

}  // namespace scatter
