// scatterd bake SCENE.json --pipeline single [--directions N --samples N --sh-order L] [--json]
#include <iostream>

#include "core/errors.hpp"
#include "pipelines/registry.hpp"
#include "tools/cache_option.hpp"
#include "tools/commands.hpp"
#include "tools/settings_option.hpp"

namespace scatter::tools {
namespace {

struct BakeOptions {
  std::string scene;
  std::string pipeline = "single";
  int directions = -1, samples = -1, sh_order = -1;  // -1: the pipeline's default
  std::vector<std::string> settings;
  CacheOptions cache;
  std::string device;
  bool json = false;
};

nlohmann::json timing_object(const std::vector<StageTime>& timings) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& t : timings) j[t.stage] = t.ms;
  return j;
}

int run_bake(const BakeOptions& o) {
  Scene scene = load_scene(o.scene);
  RenderRequest request;
  request.settings = parse_settings(o.settings);
  if (o.directions != -1) request.settings["directions"] = o.directions;
  if (o.samples != -1) request.settings["samples"] = o.samples;
  if (o.sh_order != -1) request.settings["sh_order"] = o.sh_order;
  const PipelineInfo& info = pipeline_info(o.pipeline);
  info.validate(request.settings);  // from the table: before any device or cache is opened
  request.terms = info.default_terms;
  if (!info.bakes()) {
    if (o.json)
      std::cout << nlohmann::json{{"pipeline", info.name}, {"needed", false}}.dump() << "\n";
    else
      std::cout << "pipeline " << info.name << " needs no bake\n";
    return 0;
  }
  auto cache = open_cache(o.cache);
  gpu::Gpu gpu(gpu::GpuOptions{o.device});
  auto pipeline = make_pipeline(o.pipeline, gpu, cache.get());
  std::string last_stage;
  BakeResult r = pipeline->bake(scene, request, [&](const std::string& stage, double f) {
    if (o.json) return;
    if (stage != last_stage || f >= 1)
      std::cerr << "bake: " << stage << " " << int(f * 100) << "%\n";
    last_stage = stage;
  });
  if (!r.needed) {
    if (o.json)
      std::cout << nlohmann::json{{"pipeline", pipeline->name()}, {"needed", false}}.dump() << "\n";
    else
      std::cout << "pipeline " << pipeline->name() << " needs no bake\n";
    return 0;
  }
  if (o.json) {
    nlohmann::json j = {{"pipeline", pipeline->name()},
                        {"needed", true},
                        {"key", r.key},
                        {"cache_hit", r.cache_hit},
                        {"cache_dir", cache->dir().string()},
                        {"timings_ms", timing_object(r.timings)},
                        {"bake_timings_ms", timing_object(r.bake_timings)},
                        {"stats", r.stats}};
    std::cout << j.dump() << "\n";
  } else {
    std::cout << (r.cache_hit ? "cache hit " : "baked ") << r.key << " (" << pipeline->name()
              << ")\n";
  }
  return 0;
}

}  // namespace

Handler add_bake_command(CLI::App& app) {
  auto o = std::make_shared<BakeOptions>();
  CLI::App* cmd =
      app.add_subcommand("bake", "Bake (or find in the cache) a pipeline's per-asset products");
  cmd->add_option("scene", o->scene, "Scene JSON file")->required();
  cmd->add_option("--pipeline", o->pipeline, "Pipeline name")->capture_default_str();
  cmd->add_option("--directions", o->directions, "Directions of the optical depth (single: 128)");
  cmd->add_option("--samples", o->samples, "Sample count (single: 25000)");
  cmd->add_option(
      "--sh-order", o->sh_order,
      "Spherical-harmonic bands, 2-8: 4-64 coefficients (single: 5; the paper uses up to 5)");
  cmd->add_option("--set", o->settings, "Pipeline setting key=value (repeatable)");
  add_cache_options(cmd, o->cache);
  cmd->add_option("--device", o->device, "OpenCL device: P:D or part of its name");
  cmd->add_flag("--json", o->json, "Print the key, cache hit, stage times and statistics as JSON");
  return [o] { return run_bake(*o); };
}

}  // namespace scatter::tools
