#include "pipelines/pipeline.hpp"

#include <gtest/gtest.h>

#include "../test_util.hpp"
#include "protocol/json_reader.hpp"

namespace scatter {
namespace {

TEST(PipelineFactory, MakesEveryKnownPipelineAndRejectsUnknownNames) {
  for (const auto& name : pipeline_names())
    EXPECT_EQ(make_pipeline(name, test::shared_gpu())->name(), name);
  EXPECT_EQ(pipeline_names(), (std::vector<std::string>{"auto", "surface", "reference", "thickness",
                                                        "single", "psf", "lbl"}));
  try {
    make_pipeline("magic", test::shared_gpu());
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(std::string(e.what()),
              "pipeline: unknown pipeline \"magic\" (known: auto, surface, reference, thickness, "
              "single, psf, lbl)");
  }
  EXPECT_EQ(parse_terms("multiple"), Terms::Multiple);
  EXPECT_THROW(parse_terms("everything"), ValidationError);
}

TEST(SettingsReader, DefaultsRangesAndUnknownKeys) {
  Settings s = {{"spp", 16}, {"step", 0.5}};
  SettingsReader r(s, "demo");
  EXPECT_EQ(r.integer("spp", 4, 1, 100), 16);
  EXPECT_EQ(r.number("seed", 3, 0, 10), 3);
  EXPECT_THROW(r.integer("step", 1, 0, 10), ValidationError);  // not an integer
  EXPECT_NO_THROW(r.finish());

  Settings bad = {{"spp", 1000}, {"sppp", 1}};
  SettingsReader b(bad, "demo");
  try {
    b.integer("spp", 4, 1, 100);
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(std::string(e.what()),
              "settings.spp: must be in [1, 100] for pipeline demo, got 1000");
  }
  try {
    b.finish();
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(std::string(e.what()), "settings.sppp: is not a setting of pipeline demo");
  }
}

}  // namespace
}  // namespace scatter
