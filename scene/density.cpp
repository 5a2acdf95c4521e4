#include "scene/density.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "protocol/digest.hpp"

namespace scatter {
namespace {

class ConstantDensity : public DensityField {
 public:
  explicit ConstantDensity(double v) : value_(v) {}
  double density(const Vec3&) const override { return value_; }
  bool homogeneous() const override { return true; }

 private:
  double value_;
};

class LayersDensity : public DensityField {
 public:
  LayersDensity(Vec3 axis, double thickness, std::vector<double> values)
      : axis_(axis), thickness_(thickness), values_(std::move(values)) {}
  double density(const Vec3& p) const override {
    auto k =
        static_cast<long long>(std::clamp(std::floor(dot(p, axis_) / thickness_), -1e15, 1e15));
    auto n = static_cast<long long>(values_.size());
    return values_[static_cast<size_t>(((k % n) + n) % n)];
  }

 private:
  Vec3 axis_;
  double thickness_;
  std::vector<double> values_;
};

class NoiseDensity : public DensityField {
 public:
  NoiseDensity(double scale, int octaves, double lo, double hi, bool marble, unsigned seed)
      : scale_(scale), octaves_(octaves), lo_(lo), hi_(hi), marble_(marble), seed_(seed) {}
  double density(const Vec3& p) const override {
    double n = fractal_noise(p * scale_, octaves_, seed_);
    // Marble: veins of a sine wave along x, perturbed by the noise (turbulence).
    double t = marble_ ? 0.5 + 0.5 * std::sin(scale_ * p.x * std::numbers::pi + 4.0 * n)
                       : std::clamp(0.5 + 0.5 * n, 0.0, 1.0);
    return lo_ + (hi_ - lo_) * t;
  }

 private:
  double scale_;
  int octaves_;
  double lo_, hi_;
  bool marble_;
  unsigned seed_;
};

class GridDensity : public DensityField {
 public:
  GridDensity(int nx, int ny, int nz, Aabb box, std::vector<float> data)
      : n_{nx, ny, nz}, box_(box), data_(std::move(data)) {}
  // SHA-256 of the dimensions, the box and the data.
  std::string digest() const {
    std::string head;
    char buf[64];
    for (int a = 0; a < 3; ++a) {
      std::snprintf(buf, sizeof buf, "%d %.17g %.17g ", n_[a], box_.lo[a], box_.hi[a]);
      head += buf;
    }
    return sha256_hex(head + std::string(reinterpret_cast<const char*>(data_.data()),
                                         data_.size() * sizeof(float)));
  }
  // Trilinear between voxel centres; zero outside the grid's box.
  double density(const Vec3& p) const override {
    Vec3 size = box_.size();
    double f[3];
    int i0[3];
    for (int a = 0; a < 3; ++a) {
      double u = (p[a] - box_.lo[a]) / size[a];
      if (u < 0 || u > 1) return 0;
      double x = std::clamp(u * n_[a] - 0.5, 0.0, double(n_[a] - 1));
      i0[a] = std::min(static_cast<int>(x), n_[a] - 2 < 0 ? 0 : n_[a] - 2);
      f[a] = n_[a] == 1 ? 0 : x - i0[a];
    }
    double r = 0;
    for (int c = 0; c < 8; ++c) {
      int idx[3];
      double w = 1;
      for (int a = 0; a < 3; ++a) {
        int bit = (c >> a) & 1;
        idx[a] = std::min(i0[a] + bit, n_[a] - 1);
        w *= bit ? f[a] : 1 - f[a];
      }
      r += w * data_[(size_t(idx[2]) * n_[1] + idx[1]) * n_[0] + idx[0]];
    }
    return r;
  }

 private:
  int n_[3];
  Aabb box_;
  std::vector<float> data_;
};

class BlockerDensity : public DensityField {
 public:
  BlockerDensity(Shape shape, double sigma_a, std::shared_ptr<const DensityField> inner)
      : shape_(shape), sigma_a_(sigma_a), inner_(std::move(inner)) {}
  double density(const Vec3& p) const override { return inner_->density(p); }
  bool blocked(const Vec3& p) const override { return shape_.inside(p); }
  double blocker_sigma_a() const override { return sigma_a_; }

 private:
  Shape shape_;
  double sigma_a_;
  std::shared_ptr<const DensityField> inner_;
};

std::shared_ptr<GridDensity> load_grid(JsonObject& obj, const std::filesystem::path& base_dir,
                                       const GridLimits& limits) {
  std::filesystem::path header_path = base_dir / obj.string("file", std::nullopt);
  // A regular file of bounded size: a FIFO or a device named here would block or never end.
  constexpr uintmax_t kMaxHeaderBytes = 1 << 20;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(header_path, ec))
    throw ValidationError(obj.path("file"),
                          "cannot open " + header_path.string() + ": not a regular file");
  if (std::filesystem::file_size(header_path, ec) > kMaxHeaderBytes || ec)
    throw ValidationError(obj.path("file"), "grid header " + header_path.string() +
                                                " is larger than " +
                                                std::to_string(kMaxHeaderBytes) + " bytes");
  std::ifstream in(header_path);
  if (!in) throw ValidationError(obj.path("file"), "cannot open " + header_path.string());
  std::string text((std::istreambuf_iterator<char>(in)), {});
  nlohmann::json json = parse_json(text, header_path.string());
  JsonObject h(json, header_path.filename().string());
  const auto& dims = h.array("dims", 3, 3);
  int n[3];
  for (int a = 0; a < 3; ++a) {
    if (!dims[a].is_number_integer() || dims[a].get<long long>() < 1 ||
        dims[a].get<long long>() > limits.max_dim)
      throw ValidationError(
          h.path("dims"), "each must be an integer in [1, " + std::to_string(limits.max_dim) + "]");
    n[a] = dims[a].get<int>();
  }
  h.choice("format", {"float32"}, "float32");
  // min and max as given: a box grown from the two points would take max < min for a flipped
  // axis and read the values the other way round.
  JsonObject b = h.object("bounds");
  Vec3 lo = b.vec3("min", std::nullopt, {-1e6, 1e6}), hi = b.vec3("max", std::nullopt, {-1e6, 1e6});
  b.finish();
  for (int a = 0; a < 3; ++a)
    if (hi[a] <= lo[a]) {
      std::ostringstream msg;
      msg << "max must exceed min on every axis ("
          << "xyz"[a] << ": min " << lo[a] << ", max " << hi[a] << ")";
      throw ValidationError(h.path("bounds"), msg.str());
    }
  Aabb box;
  box.add(lo);
  box.add(hi);
  std::filesystem::path data_path = header_path.parent_path() / h.string("data", std::nullopt);
  h.finish();
  size_t count = size_t(n[0]) * n[1] * n[2];
  auto bytes = std::filesystem::is_regular_file(data_path, ec)
                   ? std::filesystem::file_size(data_path, ec)
                   : 0;
  if (ec || bytes != count * sizeof(float))
    throw ValidationError(header_path.string(), "data file " + data_path.string() + " must hold " +
                                                    std::to_string(count * sizeof(float)) +
                                                    " bytes (float32, x fastest)");
  std::vector<float> data(count);
  std::ifstream raw(data_path, std::ios::binary);
  if (!raw.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(bytes)))
    throw ValidationError(header_path.string(), "cannot read data file " + data_path.string());
  for (size_t i = 0; i < count; ++i)
    if (!std::isfinite(data[i]) || data[i] < 0)
      throw ValidationError(data_path.string(),
                            "value " + std::to_string(i) + " is negative or not finite");
  return std::make_shared<GridDensity>(n[0], n[1], n[2], box, std::move(data));
}

// Hash of a lattice point to a unit gradient-ish vector.
Vec3 lattice_gradient(int x, int y, int z, unsigned seed) {
  uint32_t h = static_cast<uint32_t>(x) * 73856093u ^ static_cast<uint32_t>(y) * 19349663u ^
               static_cast<uint32_t>(z) * 83492791u ^ seed * 2654435761u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  static constexpr double g[12][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                      {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                      {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1}};
  const double* v = g[h % 12];
  return {v[0], v[1], v[2]};
}

double gradient_noise(const Vec3& p, unsigned seed) {
  int i[3];
  double f[3], w[3];
  for (int a = 0; a < 3; ++a) {
    double fl = std::clamp(std::floor(p[a]), -1e9, 1e9);
    i[a] = static_cast<int>(fl);
    f[a] = p[a] - fl;
    w[a] = f[a] * f[a] * f[a] * (f[a] * (f[a] * 6 - 15) + 10);
  }
  double r = 0;
  for (int c = 0; c < 8; ++c) {
    int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    Vec3 g = lattice_gradient(i[0] + b[0], i[1] + b[1], i[2] + b[2], seed);
    double wt = 1;
    for (int a = 0; a < 3; ++a) wt *= b[a] ? w[a] : 1 - w[a];
    r += wt * dot(g, Vec3{f[0] - b[0], f[1] - b[1], f[2] - b[2]});
  }
  return r;
}

}  // namespace

double fractal_noise(const Vec3& p, int octaves, unsigned seed) {
  double sum = 0, amp = 1, freq = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * gradient_noise(p * freq, seed + static_cast<unsigned>(o));
    norm += amp;
    amp *= 0.5;
    freq *= 2;
  }
  return sum / norm * 1.5;  // gradient noise rarely exceeds +-0.7; stretch towards +-1
}

std::shared_ptr<const DensityField> parse_density(JsonObject& obj,
                                                  const std::filesystem::path& base_dir,
                                                  const GridLimits& limits) {
  constexpr Range kDensity{0, 1e6};
  std::string type =
      obj.choice("type", {"constant", "layers", "noise", "grid", "blocker"}, "constant");
  std::shared_ptr<DensityField> field;
  std::string grid_digest;  // a grid's data
  if (type == "constant") {
    field = std::make_shared<ConstantDensity>(obj.number("value", 1.0, kDensity));
  } else if (type == "layers") {
    Vec3 axis = obj.vec3("axis", Vec3{0, 1, 0}, {-1e6, 1e6});
    if (length(axis) < 1e-9) throw ValidationError(obj.path("axis"), "must not be zero");
    double thickness = obj.number("thickness", 0.25, {1e-6, 1e6});
    field = std::make_shared<LayersDensity>(normalize(axis), thickness,
                                            obj.numbers("values", 1, 64, kDensity));
  } else if (type == "noise") {
    double scale = obj.number("scale", 3.0, {1e-6, 1e6});
    int octaves = obj.integer("octaves", 5, {1, 12});
    double lo = obj.number("min", 0.2, kDensity);
    double hi = obj.number("max", 1.0, kDensity);
    if (hi < lo) throw ValidationError(obj.path("max"), "must not be below min");
    bool marble = obj.boolean("marble", false);
    auto seed = static_cast<unsigned>(obj.integer("seed", 1, {0, 1e9}));
    field = std::make_shared<NoiseDensity>(scale, octaves, lo, hi, marble, seed);
  } else if (type == "grid") {
    auto grid = load_grid(obj, base_dir, limits);
    grid_digest = grid->digest();
    field = std::move(grid);
  } else {
    JsonObject shape_obj = obj.object("shape");
    Shape shape = Shape::parse(shape_obj);
    shape_obj.finish();
    double sigma_a = obj.number("sigma_a", 1000.0, {0, 1e6});
    std::shared_ptr<const DensityField> inner = std::make_shared<ConstantDensity>(1.0);
    if (auto inner_obj = obj.optional_object("inner")) {
      inner = parse_density(*inner_obj, base_dir, limits);
      inner_obj->finish();
    }
    field = std::make_shared<BlockerDensity>(shape, sigma_a, std::move(inner));
  }
  field->set_id(sha256_hex("density " + obj.value().dump() + " " + grid_digest));
  return field;
}

}  // namespace scatter
