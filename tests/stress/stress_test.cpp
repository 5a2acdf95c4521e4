// The numerical stress suite (docs/STRESS.md), one test per pipeline: every scene of
// stress_scenes.cpp that the pipeline renders must bake and render within a bounded time, give
// finite, non-negative radiance (and standard error), and stay under the physical bounds of
// stress_bounds.cpp where they apply. SCATTER_STRESS=long runs the long mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "../unit/test_util.hpp"
#include "core/errors.hpp"
#include "pipelines/image.hpp"
#include "pipelines/registry.hpp"
#include "stress_bounds.hpp"
#include "stress_scenes.hpp"

namespace scatter::stress {
namespace {

// Settings that keep a 16 x 16 frame of an 8^3 grid short; the defaults otherwise, since the
// defaults are what users get. SCATTER_STRESS_SET="key=value,..." overrides them (to try a
// change on the failing cases).
Settings quick(const std::string& pipeline) {
  Settings s;
  if (pipeline == "single") s = {{"samples", 200}, {"directions", 8}};
  if (pipeline == "reference" || pipeline == "auto") s = {{"spp", 6}};
  if (pipeline == "thickness") s = {{"shadow_size", 64}};
  if (const char* set = std::getenv("SCATTER_STRESS_SET")) {
    std::stringstream in(set);
    for (std::string kv; std::getline(in, kv, ',');)
      if (auto eq = kv.find('='); eq != std::string::npos)
        s[kv.substr(0, eq)] = std::stod(kv.substr(eq + 1));
  }
  return s;
}

// SCATTER_STRESS_CASES="a,b": only the cases whose names contain one of these.
bool selected(const StressCase& c) {
  const char* only = std::getenv("SCATTER_STRESS_CASES");
  if (!only) return true;
  std::stringstream in(only);
  for (std::string part; std::getline(in, part, ',');)
    if (c.name.find(part) != std::string::npos) return true;
  return false;
}

// A bake or a render that takes longer than this has hung (they take well under a second here).
double time_limit(Mode mode) {
  return mode == Mode::Long ? 120 : 20;
}

// The grid files of the shells, one folder per test: CTest may run the tests in parallel, and
// scratch_dir() empties its folder.
const std::filesystem::path& data_dir() {
  static const std::filesystem::path dir = [] {
    const auto* t = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "stress_" + std::string(t->test_suite_name()) + "_" + t->name();
    std::replace(name.begin(), name.end(), '/', '_');
    return test::scratch_dir(name);
  }();
  return dir;
}

const std::vector<StressCase>& cases() {
  static const std::vector<StressCase> all = stress_cases(mode_from_env(), data_dir());
  return all;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The terms case `index` asks of `info`: each in turn, so that every term meets every class.
Terms terms_for(const PipelineInfo& info, size_t index) {
  return info.terms[index % info.terms.size()];
}

struct Tally {
  int rendered = 0, bounded = 0, declined = 0;
  double seconds = 0;  // the slowest case
};

// Failures a pipeline is known to have, and why (docs/STRESS.md, known failures): they still
// run, and are printed and counted instead of failing the suite. Only the bound check: a NaN, a
// negative value or a hang always fails.
std::string known_failure(const std::string& pipeline, const StressCase& c,
                          const std::string& failure) {
  if (failure.rfind("energy above", 0) != 0) return "";
  if (pipeline != "single") return "";
  // A one-voxel shell several mean free paths deep, at many samples (SCATTER_STRESS_SET=
  // samples=5000: the shell at sigma_t x voxel 1000, 3.0x, not diagnosed; mixed/683, 1.24x, which
  // separate eye and light depth cuts passed). The default modes have none since 2026-12-07
  // (docs/STRESS.md); layers and noise fail the suite.
  if (c.params.density == "shell" && c.params.tau_voxel >= 1)
    return "single term above the bound: a one-voxel shell, open at many samples";
  return "";
}

// Writes DIR/NAME.json (the scene, a grid file copied beside it), NAME.exr and NAME-bound.exr.
void dump(const std::filesystem::path& dir, std::string name, const StressCase& c,
          const Image& image, const std::optional<Image>& bound) {
  std::replace(name.begin(), name.end(), '/', '_');
  const std::filesystem::path base = dir / name;
  std::filesystem::create_directories(dir);
  nlohmann::json scene = c.scene;
  // A grid file (the shells) and its data, beside the scene.
  if (auto& d = scene["medium"]["density"]; d.value("type", "") == "grid") {
    std::filesystem::path header = d["file"].get<std::string>();
    for (auto file :
         {header, header.parent_path() /
                      nlohmann::json::parse(std::ifstream(header))["data"].get<std::string>()})
      std::filesystem::copy_file(file, base.parent_path() / file.filename(),
                                 std::filesystem::copy_options::overwrite_existing);
    d["file"] = header.filename().string();
  }
  std::ofstream(base.string() + ".json") << scene.dump(2) << "\n";
  write_image(image, base.string() + ".exr");
  if (bound) write_image(*bound, base.string() + "-bound.exr");
}

class Stress : public ::testing::TestWithParam<std::string> {
 protected:
  // Renders case `c` and checks it; returns what failed.
  std::vector<std::string> run(const StressCase& c, size_t index, Tally& tally) {
    const std::string& name = GetParam();
    const PipelineInfo& info = pipeline_info(name);
    Scene scene = parse_scene(c.scene, data_dir());
    const Terms terms = terms_for(info, index);
    const RenderRequest request{terms, quick(name), nullptr};
    const double limit = time_limit(mode_from_env());
    auto pipeline = make_pipeline(name, test::shared_gpu());
    const auto start = std::chrono::steady_clock::now();
    // SCATTER_STRESS_VERBOSE=1: each case as it starts, to find one that hangs.
    if (std::getenv("SCATTER_STRESS_VERBOSE")) {
      std::printf("%s %s (%s)\n", name.c_str(), c.name.c_str(), to_string(terms).c_str());
      std::fflush(stdout);
    }
    std::vector<std::string> failed;
    RenderResult r;
    try {
      if (info.bakes()) {
        auto t0 = std::chrono::steady_clock::now();
        pipeline->bake(scene, request);
        if (seconds_since(t0) >= limit)
          failed.push_back("bake took " + std::to_string(seconds_since(t0)) + " s");
      }
      auto t0 = std::chrono::steady_clock::now();
      r = pipeline->render(scene, request);
      if (seconds_since(t0) >= limit)
        failed.push_back("render took " + std::to_string(seconds_since(t0)) + " s");
    } catch (const ValidationError& e) {
      // A pipeline may decline a scene it does not model, with a reason a user can act on.
      if (std::string(e.what()).empty()) failed.push_back("declined without a reason");
      if (std::getenv("SCATTER_STRESS_VERBOSE")) std::printf("  declined: %s\n", e.what());
      ++tally.declined;
      return failed;
    }
    ++tally.rendered;
    tally.seconds = std::max(tally.seconds, seconds_since(start));
    if (r.image.width != scene.width || r.image.height != scene.height)
      return {"the image is not the scene's size"};
    if (std::string bad = bad_value(r.image); !bad.empty()) return {"radiance: " + bad};
    if (r.std_error) {
      if (std::string bad = bad_value(*r.std_error); !bad.empty())
        failed.push_back("standard error: " + bad);
    }
    std::optional<Image> bound;
    // Every pipeline's single term takes the HG phase (lbl's too since issue 16).
    if (terms == Terms::Single) bound = single_bound(scene, false);
    if (terms == Terms::Surface) bound = surface_bound(scene);
    if (bound) {
      ++tally.bounded;
      if (std::string above = above_bound(r.image, *bound); !above.empty())
        failed.push_back("energy above the physical bound: " + above);
    }
    // SCATTER_STRESS_DUMP=DIR: each failing case's scene, image and bound, to look at.
    if (const char* dir = std::getenv("SCATTER_STRESS_DUMP"); dir && !failed.empty())
      dump(dir, name + "_" + c.name, c, r.image, bound);
    return failed;
  }
};

std::string test_name(const ::testing::TestParamInfo<std::string>& p) {
  return p.param;
}

INSTANTIATE_TEST_SUITE_P(EveryPipeline, Stress, ::testing::ValuesIn(pipeline_names()), test_name);

TEST_P(Stress, ExtremeScenes) {
  std::map<std::string, Tally> by_class;
  size_t index = 0;
  int known_failures = 0;
  for (const StressCase& c : cases()) {
    ++index;
    if (std::find(c.pipelines.begin(), c.pipelines.end(), GetParam()) == c.pipelines.end() ||
        !selected(c))
      continue;
    std::vector<std::string> failed = run(c, index, by_class[c.klass]);
    const std::string what =
        c.name + " (" + to_string(terms_for(pipeline_info(GetParam()), index)) + ")";
    for (const std::string& f : failed) {
      if (std::string known = known_failure(GetParam(), c, f); !known.empty()) {
        ++known_failures;
        std::printf("known failure %s %s [%s, density %s, sigma_t x voxel %g, g %g]: %s\n",
                    GetParam().c_str(), what.c_str(), known.c_str(), c.params.density.c_str(),
                    c.params.tau_voxel, c.params.g, f.c_str());
        continue;
      }
      ADD_FAILURE() << what << ": " << f << "\n" << c.scene.dump();
    }
  }
  if (known_failures > 0)
    std::printf("%s: %d known failures (docs/STRESS.md)\n", GetParam().c_str(), known_failures);
  for (const auto& [klass, t] : by_class) {
    std::printf("%-10s %-10s rendered %4d  bounded %4d  declined %3d  slowest %.2f s\n",
                GetParam().c_str(), klass.c_str(), t.rendered, t.bounded, t.declined, t.seconds);
    EXPECT_GT(t.rendered, 0) << GetParam() << " rendered no " << klass << " scene";
  }
}

// `single` with `settings` renders case c's single term finite and under its physical bound.
void expect_single_under_bound(const StressCase& c, const Settings& settings) {
  Scene scene = parse_scene(c.scene, data_dir());
  auto pipeline = make_pipeline("single", test::shared_gpu());
  const RenderRequest request{Terms::Single, settings, nullptr};
  pipeline->bake(scene, request);
  const RenderResult r = pipeline->render(scene, request);
  EXPECT_EQ(bad_value(r.image), "") << c.name;
  const std::optional<Image> bound = single_bound(scene, false);
  ASSERT_TRUE(bound) << c.name;
  EXPECT_EQ(above_bound(r.image, *bound), "") << c.name;
}

// One-voxel shells seen from inside, several mean free paths a voxel (long mode), with samples
// enough to resolve the shell: under `single` they stay under the bound since the splat clips to
// the quadratic transmittance model's own zero set (before: 32x-21,000x; docs/STRESS.md), and
// since a camera inside the object integrates from the eye to the first surface and takes the
// phase per view ray (mixed/109, g 0.9: 1.08x before).
TEST(SingleShells, InsideUnderTheBoundWithEnoughSamples) {
  const std::vector<StressCase> all = stress_cases(Mode::Long, data_dir());
  const PipelineInfo& info = pipeline_info("single");
  const std::vector<std::string> names = {"mixed/109", "mixed/718", "mixed/914", "mixed/1096",
                                          "mixed/1278"};
  int checked = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    const StressCase& c = all[i];
    if (std::find(names.begin(), names.end(), c.name) == names.end()) continue;
    ASSERT_EQ(c.params.density, "shell") << c.name;
    ASSERT_EQ(terms_for(info, i + 1), Terms::Single) << c.name;  // as ExtremeScenes numbers them
    expect_single_under_bound(c, {{"samples", 5000}, {"directions", 8}});
    ++checked;
  }
  EXPECT_EQ(checked, int(names.size()));
}

// Dense skins from the long mode that single once put above the bound (docs/STRESS.md): a
// one-voxel slab at sigma_t x voxel 1000 at the suite's settings (6.7x: the optical depth's
// differences stepped over the slab), and, at 5,000 samples with mesh_bound, a constant torus at
// 30 under a grazing light (mixed/1726, 1.58x) and a torus around a blocker at 1000 (mixed/1775,
// 1.57x), whose boundary voxels' mean extinction was a tenth of the mesh's sliver.
TEST(SingleDense, UnderTheBound) {
  const std::vector<StressCase> all = stress_cases(Mode::Long, data_dir());
  const PipelineInfo& info = pipeline_info("single");
  const std::map<std::string, Settings> cases = {
      {"shell/slab_tau=1000", {{"samples", 200}, {"directions", 8}}},
      {"mixed/1726", {{"samples", 5000}, {"directions", 8}, {"mesh_bound", 1}}},
      {"mixed/1775", {{"samples", 5000}, {"directions", 8}, {"mesh_bound", 1}}}};
  int checked = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    const StressCase& c = all[i];
    auto found = cases.find(c.name);
    if (found == cases.end()) continue;
    ASSERT_EQ(terms_for(info, i + 1), Terms::Single) << c.name;  // as ExtremeScenes numbers them
    expect_single_under_bound(c, found->second);
    ++checked;
  }
  EXPECT_EQ(checked, int(cases.size()));
}

// The suite is as large as docs/STRESS.md says, and every extreme the parser rejects is rejected
// with a ValidationError that names the field.
TEST(StressSuite, SizeAndRejections) {
  const auto& all = cases();
  EXPECT_GE(all.size(), 500u);
  std::map<std::string, int> per_class;
  for (const StressCase& c : all) {
    ++per_class[c.klass];
    if (!c.rejected.empty()) {
      EXPECT_NE(c.rejected.find("scene.medium.sigma_"), std::string::npos)
          << c.name << ": " << c.rejected;
    }
    EXPECT_NO_THROW(parse_scene(c.scene, data_dir())) << c.name;
  }
  for (const auto& [klass, n] : per_class) std::printf("%-10s %4d scenes\n", klass.c_str(), n);
}

}  // namespace
}  // namespace scatter::stress
