// The single pipeline's bake product as bytes for the BakeCache: a flat little-endian record
// (magic, parameters, arrays each with its length, stage times). deserialize() checks every length.
#include <cstring>
#include <stdexcept>

#include "pipelines/single/sh.hpp"
#include "pipelines/single/single_bake.hpp"

namespace scatter {
namespace {

// ---- Serialisation: a flat little-endian record -----------------------------------------------

constexpr uint32_t kMagic = 0x37425353;  // "SSB7": with the coarse set's weights

class Writer {
 public:
  template <class T>
  void put(const T& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void put_floats(const std::vector<float>& v) {
    put<uint64_t>(v.size());
    out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
  }
  std::string out;
};

class Reader {
 public:
  explicit Reader(const std::string& s) : s_(s) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, s_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::vector<float> get_floats(size_t expected) {
    uint64_t n = get<uint64_t>();
    if (n != expected)
      throw std::runtime_error("single bake: array of " + std::to_string(n) + " floats where " +
                               std::to_string(expected) + " belong");
    need(n * sizeof(float));
    std::vector<float> v(n);
    std::memcpy(v.data(), s_.data() + at_, n * sizeof(float));
    at_ += n * sizeof(float);
    return v;
  }
  bool done() const { return at_ == s_.size(); }

 private:
  void need(size_t n) {
    if (s_.size() - at_ < n) throw std::runtime_error("single bake: truncated record");
  }
  const std::string& s_;
  size_t at_ = 0;
};

}  // namespace

std::string SingleBake::serialize() const {
  Writer w;
  w.put(kMagic);
  w.put<int32_t>(params.directions);
  w.put<int32_t>(params.samples);
  w.put<int32_t>(params.sh_order);
  w.put<int32_t>(params.sh_depth);
  w.put<double>(params.radius);
  w.put<int32_t>(params.candidates);
  w.put<int32_t>(params.density_guide);
  w.put<int32_t>(params.sigma_fit);
  w.put<int32_t>(params.weight_fit);
  w.put<double>(params.split);
  w.put<double>(params.adapt);
  w.put<uint32_t>(params.seed);
  w.put<int32_t>(count);
  w.put<int32_t>(split);
  w.put<double>(coverage_mean);
  w.put<double>(coverage_spread);
  w.put_floats(position);
  w.put_floats(depth_at);
  w.put_floats(sigma);
  w.put_floats(weight);
  w.put_floats(sigma_s);
  w.put_floats(plane);
  w.put<int32_t>(coarse_weight.empty() ? 0 : 1);
  if (!coarse_weight.empty()) w.put_floats(coarse_weight);
  w.put_floats(sh);
  w.put<uint32_t>(static_cast<uint32_t>(timings.size()));
  for (const StageTime& t : timings) {
    w.put<uint32_t>(static_cast<uint32_t>(t.stage.size()));
    w.out += t.stage;
    w.put<double>(t.ms);
  }
  return std::move(w.out);
}

SingleBake SingleBake::deserialize(const std::string& bytes) {
  Reader r(bytes);
  if (r.get<uint32_t>() != kMagic)
    throw std::runtime_error("single bake: not a single-scattering bake");
  SingleBake b;
  b.params.directions = r.get<int32_t>();
  b.params.samples = r.get<int32_t>();
  b.params.sh_order = r.get<int32_t>();
  b.params.sh_depth = r.get<int32_t>() != 0;
  b.params.radius = r.get<double>();
  b.params.candidates = r.get<int32_t>();
  b.params.density_guide = r.get<int32_t>() != 0;
  b.params.sigma_fit = r.get<int32_t>();
  b.params.weight_fit = r.get<int32_t>();
  b.params.split = r.get<double>();
  b.params.adapt = r.get<double>();
  b.params.seed = r.get<uint32_t>();
  b.count = r.get<int32_t>();
  b.split = r.get<int32_t>();
  if (b.count < 0 || b.params.sh_order < 1 || b.params.sh_order > kMaxShBands)
    throw std::runtime_error("single bake: bad header");
  b.coverage_mean = r.get<double>();
  b.coverage_spread = r.get<double>();
  const size_t n = size_t(b.count);
  b.position = r.get_floats(3 * n);
  b.depth_at = r.get_floats(3 * n);
  b.sigma = r.get_floats(n);
  b.weight = r.get_floats(n);
  b.sigma_s = r.get_floats(3 * n);
  b.plane = r.get_floats(4 * n);
  if (r.get<int32_t>() != 0) b.coarse_weight = r.get_floats(n);
  b.sh = r.get_floats(3 * n * b.coefficients());
  uint32_t stages = r.get<uint32_t>();
  if (stages > 64) throw std::runtime_error("single bake: bad stage list");
  for (uint32_t i = 0; i < stages; ++i) {
    uint32_t len = r.get<uint32_t>();
    if (len > 256) throw std::runtime_error("single bake: bad stage name");
    std::string name;
    for (uint32_t c = 0; c < len; ++c) name += r.get<char>();
    b.timings.push_back({name, r.get<double>()});
  }
  if (!r.done()) throw std::runtime_error("single bake: trailing bytes");
  return b;
}

}  // namespace scatter
