#include "pipelines/accumulate.hpp"

#include <cmath>
#include <stdexcept>

namespace scatter {

void PassAccumulator::add(const Image& mean, const Image& std_error, int samples) {
  if (samples < 1) throw std::invalid_argument("a pass needs at least one sample");
  if (mean.width != std_error.width || mean.height != std_error.height)
    throw std::invalid_argument("a pass's mean and standard error differ in size");
  if (passes_ == 0) {
    width_ = mean.width;
    height_ = mean.height;
    weighted_sum_.assign(mean.rgb.size(), 0.0);
    variance_sum_.assign(mean.rgb.size(), 0.0);
  } else if (mean.width != width_ || mean.height != height_) {
    throw std::invalid_argument("a pass differs in size from the passes before");
  }
  const double n = samples;
  for (size_t i = 0; i < mean.rgb.size(); ++i) {
    weighted_sum_[i] += n * mean.rgb[i];
    variance_sum_[i] += n * n * double(std_error.rgb[i]) * std_error.rgb[i];
  }
  samples_ += samples;
  ++passes_;
}

void PassAccumulator::clear() {
  *this = PassAccumulator();
}

Image PassAccumulator::mean() const {
  if (empty()) return {};
  Image m(width_, height_);
  for (size_t i = 0; i < m.rgb.size(); ++i)
    m.rgb[i] = static_cast<float>(weighted_sum_[i] / double(samples_));
  return m;
}

Image PassAccumulator::std_error() const {
  if (empty()) return {};
  Image se(width_, height_);
  for (size_t i = 0; i < se.rgb.size(); ++i)
    se.rgb[i] = static_cast<float>(std::sqrt(variance_sum_[i]) / double(samples_));
  return se;
}

}  // namespace scatter
