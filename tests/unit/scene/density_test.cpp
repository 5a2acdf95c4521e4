#include "scene/density.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <future>
#include <limits>
#include <thread>

#include "../test_util.hpp"

namespace scatter {
namespace {

std::shared_ptr<const DensityField> make(const nlohmann::json& j,
                                         const std::filesystem::path& dir = ".") {
  JsonObject o(j, "density");
  auto f = parse_density(o, dir);
  o.finish();
  return f;
}

TEST(Density, LayersAlternateAlongTheAxis) {
  auto f = make({{"type", "layers"}, {"axis", {0, 2, 0}}, {"thickness", 0.5}, {"values", {1, 3}}});
  EXPECT_EQ(f->density({0, 0.1, 0}), 1);
  EXPECT_EQ(f->density({5, 0.6, -2}), 3);
  EXPECT_EQ(f->density({0, -0.1, 0}), 3);
  EXPECT_EQ(f->density({0, 1.1, 0}), 1);
  EXPECT_FALSE(f->homogeneous());
}

TEST(Density, NoiseStaysInRangeAndRepeatsForASeed) {
  for (bool marble : {false, true}) {
    auto f = make({{"type", "noise"}, {"min", 0.2}, {"max", 0.9}, {"marble", marble}, {"seed", 3}});
    auto g = make({{"type", "noise"}, {"min", 0.2}, {"max", 0.9}, {"marble", marble}, {"seed", 3}});
    double lo = 1e9, hi = -1e9;
    for (int i = 0; i < 2000; ++i) {
      Vec3 p{std::sin(i * 1.3) * 2, std::cos(i * 0.7) * 2, (i % 17) * 0.1 - 0.8};
      double d = f->density(p);
      EXPECT_EQ(d, g->density(p));
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    EXPECT_GE(lo, 0.2);
    EXPECT_LE(hi, 0.9);
    EXPECT_GT(hi - lo, 0.3) << "the noise should vary";
  }
}

TEST(Density, GridFileIsInterpolatedAndValidated) {
  auto dir = test::scratch_dir("density_grid");
  // 2x1x1 grid over [0,2]x[0,1]x[0,1]: values 1 and 3 at voxel centres x = 0.5 and 1.5.
  float data[2] = {1.f, 3.f};
  test::write_file(dir / "g.raw", std::string(reinterpret_cast<char*>(data), sizeof data));
  test::write_file(dir / "g.json", R"({"dims": [2, 1, 1], "data": "g.raw", "format": "float32",
                                       "bounds": {"min": [0, 0, 0], "max": [2, 1, 1]}})");
  auto f = make({{"type", "grid"}, {"file", "g.json"}}, dir);
  EXPECT_NEAR(f->density({1.0, 0.5, 0.5}), 2.0, 1e-9);
  EXPECT_NEAR(f->density({0.5, 0.2, 0.9}), 1.0, 1e-9);
  EXPECT_NEAR(f->density({1.75, 0.5, 0.5}), 3.0, 1e-9);
  EXPECT_EQ(f->density({2.5, 0.5, 0.5}), 0.0);

  test::write_file(dir / "short.json", R"({"dims": [4, 1, 1], "data": "g.raw",
                                           "bounds": {"min": [0, 0, 0], "max": [2, 1, 1]}})");
  try {
    make({{"type", "grid"}, {"file", "short.json"}}, dir);
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("must hold 16 bytes"), std::string::npos) << e.what();
  }
  test::write_file(dir / "huge.json", R"({"dims": [4096, 1, 1], "data": "g.raw",
                                          "bounds": {"min": [0, 0, 0], "max": [2, 1, 1]}})");
  EXPECT_THROW(make({{"type", "grid"}, {"file", "huge.json"}}, dir), ValidationError);
  float bad[2] = {1.f, -1.f};
  test::write_file(dir / "g.raw", std::string(reinterpret_cast<char*>(bad), sizeof bad));
  EXPECT_THROW(make({{"type", "grid"}, {"file", "g.json"}}, dir), ValidationError);
}

// Grid files that lie or hold what a density cannot be: each a ValidationError naming the problem.
TEST(Density, GridFilesThatLieAreRejected) {
  auto dir = test::scratch_dir("density_grid_lies");
  auto error = [&](const std::string& header, const std::string& raw) -> std::string {
    test::write_file(dir / "g.raw", raw);
    test::write_file(dir / "g.json", header);
    try {
      make({{"type", "grid"}, {"file", "g.json"}}, dir);
    } catch (const ValidationError& e) {
      return e.what();
    }
    ADD_FAILURE() << "accepted " << header;
    return "";
  };
  auto floats = [](std::vector<float> v) {
    return std::string(reinterpret_cast<const char*>(v.data()), v.size() * 4);
  };
  const std::string bounds = R"("bounds": {"min": [0, 0, 0], "max": [1, 1, 1]})";
  auto header = [&](const std::string& dims) {
    return R"({"dims": )" + dims + R"(, "data": "g.raw", )" + bounds + "}";
  };
  // More data than the dims say, as well as less.
  EXPECT_NE(error(header("[1, 1, 1]"), floats({1, 2})).find("must hold 4 bytes"),
            std::string::npos);
  EXPECT_NE(error(header("[2, 1, 1]"), floats({1})).find("must hold 8 bytes"), std::string::npos);
  for (float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.5f})
    EXPECT_NE(
        error(header("[2, 1, 1]"), floats({1, bad})).find("value 1 is negative or not finite"),
        std::string::npos);
  for (const char* dims :
       {"[0, 1, 1]", "[-2, 1, 1]", "[2.5, 1, 1]", "[2, 1]", "[513, 512, 512]", "[1e10, 1, 1]"})
    EXPECT_NE(error(header(dims), floats({1})).find("dims"), std::string::npos) << dims;
  // An empty axis, and a flipped one (max below min: refused, not read as the box the two
  // corners span).
  for (auto [min, message] :
       {std::pair{"[0, 0, 0]", "(y: min 0, max 0)"}, std::pair{"[0, 1, 0]", "(y: min 1, max 0)"}}) {
    std::string grid = std::string(R"({"dims": [1, 1, 1], "data": "g.raw", "bounds": {"min": )") +
                       min + R"(, "max": [1, 0, 1]}})";
    EXPECT_NE(
        error(grid, floats({1})).find(std::string("max must exceed min on every axis ") + message),
        std::string::npos)
        << min;
  }
  EXPECT_NE(error(R"({"dims": [1, 1, 1], "data": "g.raw")", floats({1})).find("not valid JSON"),
            std::string::npos);
}

// A grid header or data file that is a FIFO is refused at once, not read (which would block).
TEST(Density, GridFilesThatAreNotRegularFilesAreRefused) {
  auto dir = test::scratch_dir("density_grid_fifo");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  auto done = std::make_shared<std::promise<std::string>>();
  auto result = done->get_future();
  test::write_file(
      dir / "g.json",
      R"({"dims": [1, 1, 1], "data": "fifo", "bounds": {"min": [0, 0, 0], "max": [1, 1, 1]}})");
  std::thread([done, dir] {
    std::string errors;
    for (const char* file : {"fifo", "g.json"}) {
      try {
        make({{"type", "grid"}, {"file", file}}, dir);
      } catch (const ValidationError& e) {
        errors += std::string(e.what()) + "\n";
      }
    }
    done->set_value(errors);
  }).detach();
  ASSERT_EQ(result.wait_for(std::chrono::seconds(10)), std::future_status::ready)
      << "reading a FIFO blocked";
  std::string errors = result.get();
  EXPECT_NE(errors.find("not a regular file"), std::string::npos) << errors;
  EXPECT_NE(errors.find("must hold 4 bytes"), std::string::npos) << errors;
}

}  // namespace
}  // namespace scatter
