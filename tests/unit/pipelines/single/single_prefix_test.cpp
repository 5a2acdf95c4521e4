// The coarse set (setting `coarse`): the bake's samples in progressive order, of which the live
// view's moving frames splat the first quarter, widened, with weights fitted for them
// (pipelines/single/single_prefix.cpp).
#include <algorithm>
#include <cmath>
#include <random>

#include "pipelines/single/sampling.hpp"
#include "single_fixture.hpp"

namespace scatter::single_test {
namespace {

// The pieces a frame splats as a bake of their own, sigma widened and weighted as the frame does.
SingleBake drawn_of(const SingleBake& b, bool coarse) {
  DrawnSamples d = drawn_samples(b, coarse);
  SingleBake p;
  p.params = b.params;
  for (const auto& [first, count] : d.ranges)
    for (int i = first; i < first + count; ++i) {
      p.position.insert(p.position.end(), &b.position[3 * size_t(i)],
                        &b.position[3 * size_t(i) + 3]);
      p.sigma.push_back(float(b.sigma[size_t(i)] * d.sigma_scale));
      p.weight.push_back((d.coarse ? b.coarse_weight : b.weight)[size_t(i)]);
      p.plane.insert(p.plane.end(), &b.plane[4 * size_t(i)], &b.plane[4 * size_t(i) + 4]);
    }
  p.count = d.count();
  return p;
}

// Each halving's prefix is Poisson-disk: its closest pair is about 2^(1/3) per halving farther
// apart than the whole's (a random half's would be no farther than the whole's).
TEST(ProgressiveOrder, EveryHalvingsPrefixIsPoissonDisk) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> candidates(20000);
  for (Vec3& c : candidates) c = {u(rng), u(rng), u(rng)};
  std::vector<float> q(candidates.size(), 1.f);
  EliminationResult kept = eliminate_samples(candidates, q, 1.0, 4000);
  std::vector<Vec3> points;
  for (int k : kept.kept) points.push_back(candidates[size_t(k)]);
  std::vector<float> pq(points.size(), 1.f);
  std::vector<int> order = progressive_order(points, pq, 1.0);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], int(i));  // a permutation
  const double whole = min_normalized_distance(points, pq);
  for (int n : {2000, 1000}) {
    std::vector<Vec3> prefix;
    for (int i = 0; i < n; ++i) prefix.push_back(points[size_t(order[size_t(i)])]);
    const double d = min_normalized_distance(prefix, std::vector<float>(prefix.size(), 1.f));
    const double ideal = std::cbrt(4000.0 / n);
    std::printf("first %d of 4000: closest pair %.4f, the whole's x %.3f (ideal %.3f)\n", n, d,
                d / whole, ideal);
    EXPECT_GT(d / whole, 0.85 * ideal) << n;
  }
}

// The coarse set's own weights make its widened Gaussians a partition of one as well as the whole
// set's are (the whole set's weights would not: they correct the whole's local crowding).
TEST(SingleBake, CoarseSetSumsToAboutOneInside) {
  SingleBake b = small_sphere_bake();
  ASSERT_EQ(b.coarse_weight.size(), size_t(b.count));
  EXPECT_EQ(SingleBake::deserialize(b.serialize()).coarse_weight, b.coarse_weight);  // kept
  SingleBake whole = drawn_of(b, false), coarse = drawn_of(b, true);
  ASSERT_EQ(coarse.count, coarse_count(6000));
  auto [mean_whole, spread_whole] = coverage(whole);
  auto [mean, spread] = coverage(coarse);
  std::printf("coverage: whole %.4f +- %.4f, coarse (%d) %.4f +- %.4f\n", mean_whole, spread_whole,
              coarse.count, mean, spread);
  EXPECT_NEAR(mean, 1.0, 0.03);
  EXPECT_LT(spread, 1.25 * spread_whole);
  // The whole set's weights on the coarse set's widened Gaussians: measured +-0.26.
  SingleBake unfitted = coarse;
  for (int i = 0; i < coarse.count; ++i) unfitted.weight[size_t(i)] = b.weight[size_t(i)];
  EXPECT_GT(coverage(unfitted).second, 2 * spread);
}

// A coarse frame stays near the full one, says so in its plan, and needs exact_tr.
TEST_F(SinglePipelineTest, CoarseFrameIsNearTheFullOne) {
  Scene s = small_sphere(64, 32);
  const Settings full = {{"samples", 20000}, {"directions", 64}, {"tr_gradient", 0}};
  Settings coarse = full;
  coarse["coarse"] = 1;
  Image a = pipeline().render(s, {Terms::Single, full, nullptr}).image;
  RenderResult r = pipeline().render(s, {Terms::Single, coarse, nullptr});
  double err = 0, ref = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    double d = double(r.image.rgb[i]) - a.rgb[i];
    err += d * d;
    ref += double(a.rgb[i]) * a.rgb[i];
  }
  const double rel = std::sqrt(err / ref);
  std::printf("coarse against full: %.4f relative RMSE, mean ratio %.4f\n", rel,
              mean_ratio(r.image, a));
  EXPECT_LT(rel, 0.09);  // measured 0.071
  EXPECT_NEAR(mean_ratio(r.image, a), 1.0, 0.03);
  bool said = false;
  for (const StagePlan& st : r.plan.stages)
    if (st.name == "splat")
      said = st.reason.find("the coarse set: 5000 of the") != std::string::npos;
  EXPECT_TRUE(said);
  coarse["exact_tr"] = 0;
  RenderResult sh = pipeline().render(s, {Terms::Single, coarse, nullptr});
  for (const StagePlan& st : sh.plan.stages)
    if (st.name == "splat") {
      EXPECT_NE(st.reason.find("coarse needs exact_tr"), std::string::npos);
    }
}

// A frame without the gradient reuses a light's pass made with it (the moving frames after a
// still one): no new light pass.
TEST_F(SinglePipelineTest, FrameWithoutGradientReusesTheLightsPass) {
  Scene s = small_sphere(32, 32);
  Settings on = {{"samples", 20000}, {"directions", 64}};
  Settings off = on;
  off["tr_gradient"] = 0;
  SinglePipeline& p = pipeline();
  p.render(s, {Terms::Single, on, nullptr});
  const int passes = p.light_passes();
  p.render(s, {Terms::Single, off, nullptr});
  EXPECT_EQ(p.light_passes(), passes);
  p.render(s, {Terms::Single, on, nullptr});
  EXPECT_EQ(p.light_passes(), passes);
}

}  // namespace
}  // namespace scatter::single_test
