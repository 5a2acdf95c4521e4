// Monte Carlo estimates of one image from independent passes (different seeds), combined into
// one: pass i with n_i samples, mean m_i and standard error se_i gives
//
//   mean = sum(n_i m_i) / N,   se^2 = sum(n_i^2 se_i^2) / N^2,   N = sum(n_i)
//
// per pixel and channel: the mean of all N samples, and its standard error (each pass's sample
// variance weighted by its count). A live view's refinement adds a pass at a time.
#pragma once

#include "pipelines/image.hpp"

namespace scatter {

class PassAccumulator {
 public:
  // Adds a pass of `samples` samples per pixel. Throws std::invalid_argument when its size differs
  // from the passes before, the two images differ in size, or samples < 1.
  void add(const Image& mean, const Image& std_error, int samples);
  void clear();

  long long samples() const { return samples_; }  // N
  int passes() const { return passes_; }
  bool empty() const { return passes_ == 0; }
  Image mean() const;       // empty before the first pass
  Image std_error() const;  // empty before the first pass

 private:
  int width_ = 0, height_ = 0, passes_ = 0;
  long long samples_ = 0;
  std::vector<double> weighted_sum_;  // sum(n_i m_i)
  std::vector<double> variance_sum_;  // sum(n_i^2 se_i^2)
};

}  // namespace scatter
