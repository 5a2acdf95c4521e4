// scatterd render SCENE.json --pipeline NAME --out FILE [--terms T] [--width W --height H] [--json]
#include <cmath>
#include <filesystem>
#include <iostream>

#include "core/errors.hpp"
#include "pipelines/budget/planner.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"
#include "tools/cache_option.hpp"
#include "tools/commands.hpp"
#include "tools/settings_option.hpp"

namespace scatter::tools {
namespace {

struct RenderOptions {
  std::string scene;
  std::string pipeline = "surface";
  std::string out;
  std::string terms;
  int width = -1, height = -1;  // -1: as the scene says
  double exposure = 1.0;
  double max_error = 0;  // 0: none
  std::string device;
  std::vector<std::string> settings;
  CacheOptions cache;
  bool json = false;
};

// Mean radiance per channel and the fraction of pixels that differ from the background: a quick
// check that a render shows something.
nlohmann::json image_stats(const Image& image, const Vec3& background) {
  double mean[3] = {0, 0, 0};
  size_t covered = 0, pixels = size_t(image.width) * image.height;
  for (size_t p = 0; p < pixels; ++p) {
    bool differs = false;
    for (int c = 0; c < 3; ++c) {
      mean[c] += image.rgb[3 * p + c];
      differs = differs || std::abs(image.rgb[3 * p + c] - background[c]) > 1e-6;
    }
    covered += differs;
  }
  return {{"mean", {mean[0] / pixels, mean[1] / pixels, mean[2] / pixels}},
          {"coverage", double(covered) / pixels}};
}

// "out.exr" -> "out.stderr.exr": where the standard error of a Monte Carlo render goes.
std::filesystem::path std_error_path(const std::filesystem::path& out) {
  auto p = out;
  return p.replace_extension(".stderr" + out.extension().string());
}

int run_render(const RenderOptions& o) {
  SceneLimits limits;
  Scene scene = load_scene(o.scene, limits);
  auto check_side = [&](int v, const char* name) {
    if (v != -1 && (v < 1 || v > limits.max_image))
      throw ValidationError(name, "must be in [1, " + std::to_string(limits.max_image) + "], got " +
                                      std::to_string(v));
  };
  check_side(o.width, "--width");
  check_side(o.height, "--height");
  if (o.width > 0) scene.width = o.width;
  if (o.height > 0) scene.height = o.height;
  check_image_path(o.out);  // before the render, not after it

  gpu::Gpu gpu(gpu::GpuOptions{o.device});
  auto cache = open_cache(o.cache);
  auto pipeline = make_pipeline(o.pipeline, gpu, cache.get());
  RenderRequest request;
  request.settings = parse_settings(o.settings);
  if (o.max_error != 0) {
    check_budget(o.pipeline, o.max_error, "--max-error");
    request.max_error = o.max_error;
  }
  if (!o.terms.empty()) {
    request.terms = parse_terms(o.terms);
  } else {
    auto ok = pipeline->supported_terms();
    request.terms =
        std::find(ok.begin(), ok.end(), Terms::All) != ok.end() ? Terms::All : ok.front();
  }
  RenderResult result = pipeline->render(scene, request);
  write_image(result.image, o.out, ToneMap{o.exposure});
  std::string std_error_file;
  if (result.std_error) {
    std_error_file = std_error_path(o.out).string();
    write_image(*result.std_error, std_error_file, ToneMap{o.exposure});
  }

  if (o.json) {
    // What it was expected to cost (pipelines/cost.hpp), beside what it took: auto's estimate is
    // of the way it picks without the cache's bakes, and a budget's path tracer at its expected
    // samples.
    const CostEstimate expected = estimate_cost(o.pipeline, scene, request);
    nlohmann::json timings = nlohmann::json::object();
    double total = 0;
    for (const auto& t : result.timings) {
      timings[t.stage] = t.ms;
      total += t.ms;
    }
    nlohmann::json j = {{"pipeline", pipeline->name()},
                        {"terms", to_string(request.terms)},
                        {"plan", result.plan},
                        {"timings_ms", timings},
                        {"total_ms", total},
                        {"estimate",
                         {{"seconds", expected.seconds},
                          {"host_bytes", expected.host_bytes},
                          {"device_bytes", expected.device_bytes},
                          {"time_field", expected.time_field},
                          {"summary", expected.summary}}},
                        {"output", o.out},
                        {"width", result.image.width},
                        {"height", result.image.height}};
    if (!std_error_file.empty()) j["std_error_output"] = std_error_file;
    if (result.error_estimate) j["error_estimate"] = *result.error_estimate;
    j["stats"] = image_stats(result.image, scene.background);
    std::cout << j.dump() << "\n";
  } else {
    std::cout << "wrote " << o.out << " (" << result.image.width << "x" << result.image.height
              << ", " << pipeline->name() << ")\n";
  }
  return 0;
}

}  // namespace

Handler add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to an image file");
  cmd->add_option("scene", o->scene, "Scene JSON file")->required();
  cmd->add_option("--pipeline", o->pipeline, "Pipeline name")->capture_default_str();
  cmd->add_option("--out", o->out, "Output image (.exr linear, .png/.jpg sRGB)")->required();
  cmd->add_option("--terms", o->terms,
                  "surface, single, multiple or all (default: all the pipeline renders)");
  cmd->add_option("--width", o->width, "Override the scene's image width");
  cmd->add_option("--height", o->height, "Override the scene's image height");
  cmd->add_option("--exposure", o->exposure, "Multiplier before tone mapping (PNG, JPEG)")
      ->capture_default_str();
  cmd->add_option("--device", o->device, "OpenCL device: P:D or part of its name");
  cmd->add_option("--set", o->settings, "Pipeline setting key=value (repeatable), e.g. spp=256");
  cmd->add_option("--max-error", o->max_error,
                  "The error accepted, a relative RMSE against the reference (auto plans by it; "
                  "the reference samples until it is met), e.g. 0.05");
  add_cache_options(cmd, o->cache);
  cmd->add_flag("--json", o->json,
                "Print the plan, per-stage milliseconds and the cost estimate as one JSON object");
  return [o] { return run_render(*o); };
}

}  // namespace scatter::tools
