#include "pipelines/accumulate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pipelines/metrics.hpp"

namespace scatter {
namespace {

// A pass's estimate from its samples: the mean and the standard error of the mean (sample
// variance with n - 1), per value, as the reference pipeline reports them.
struct Pass {
  Image mean, std_error;
  int n;
};

Pass estimate(const std::vector<std::vector<double>>& samples, int w, int h) {
  Pass p{Image(w, h), Image(w, h), static_cast<int>(samples[0].size())};
  for (size_t i = 0; i < samples.size(); ++i) {
    double n = double(p.n), sum = 0, sq = 0;
    for (double x : samples[i]) sum += x, sq += x * x;
    double m = sum / n, var = (sq - n * m * m) / (n - 1);
    p.mean.rgb[i] = float(m);
    p.std_error.rgb[i] = float(std::sqrt(var / n));
  }
  return p;
}

TEST(PassAccumulatorTest, CombinesPassesAsTheDirectComputationOverAllTheirSamples) {
  const int w = 3, h = 2, values = w * h * 3;
  std::mt19937 rng(7);
  std::vector<std::vector<double>> all(values);
  PassAccumulator acc;
  const int counts[] = {40, 400, 120, 9};
  double direct_sum[18] = {}, direct_var[18] = {};
  long long total = 0;
  for (int n : counts) {
    std::vector<std::vector<double>> samples(values);
    for (int i = 0; i < values; ++i) {
      std::exponential_distribution<double> d(1.0 / (1 + i));  // mean 1 + i, sd 1 + i
      for (int k = 0; k < n; ++k) samples[i].push_back(d(rng));
      all[i].insert(all[i].end(), samples[i].begin(), samples[i].end());
    }
    Pass p = estimate(samples, w, h);
    acc.add(p.mean, p.std_error, p.n);
    total += n;
    for (int i = 0; i < values; ++i) {
      direct_sum[i] += double(n) * p.mean.rgb[i];
      direct_var[i] += double(n) * n * p.std_error.rgb[i] * p.std_error.rgb[i];
    }
  }
  EXPECT_EQ(acc.samples(), total);
  EXPECT_EQ(acc.passes(), 4);
  Image mean = acc.mean(), se = acc.std_error();
  Pass pooled = estimate(all, w, h);  // one estimate from every sample at once
  for (int i = 0; i < values; ++i) {
    // The formula: sum(n_i m_i) / N and sqrt(sum(n_i^2 se_i^2)) / N.
    EXPECT_NEAR(mean.rgb[i], direct_sum[i] / total, 1e-5 * (1 + i));
    EXPECT_NEAR(se.rgb[i], std::sqrt(direct_var[i]) / total, 1e-6 * (1 + i));
    // The mean of all samples, exactly; their standard error within the spread of the pass
    // means (5 % at 569 samples of an exponential).
    EXPECT_NEAR(mean.rgb[i], pooled.mean.rgb[i], 1e-5 * (1 + i));
    EXPECT_NEAR(se.rgb[i], pooled.std_error.rgb[i], 0.05 * pooled.std_error.rgb[i]);
  }
  // Its estimated error falls as 1/sqrt(N): four times the samples, half the error.
  PassAccumulator twice;
  Image m(1, 1), e(1, 1);
  m.rgb = {1, 1, 1};
  e.rgb = {0.2f, 0.2f, 0.2f};
  twice.add(m, e, 10);
  for (int k = 0; k < 3; ++k) twice.add(m, e, 10);
  EXPECT_NEAR(relative_norm(twice.std_error(), twice.mean()), 0.1, 1e-6);
}

TEST(PassAccumulatorTest, RefusesPassesOfAnotherSize) {
  PassAccumulator acc;
  EXPECT_TRUE(acc.empty());
  EXPECT_EQ(acc.mean().width, 0);
  acc.add(Image(4, 4), Image(4, 4), 3);
  EXPECT_THROW(acc.add(Image(4, 2), Image(4, 2), 3), std::invalid_argument);
  EXPECT_THROW(acc.add(Image(4, 4), Image(2, 2), 3), std::invalid_argument);
  EXPECT_THROW(acc.add(Image(4, 4), Image(4, 4), 0), std::invalid_argument);
  acc.clear();
  EXPECT_NO_THROW(acc.add(Image(2, 2), Image(2, 2), 3));
}

}  // namespace
}  // namespace scatter
