// scatterd bench SCENE.json --pipeline NAME [--terms T] --sweep key=v1,v2,... [--set k=v ...]
//                [--reference FILE.exr] [--reference-spp N] [--frames N] --csv OUT.csv
// scatterd bench --calibrate TABLE.json [--quick] [--reuse] [--size N] [--voxels N] [SCENE.json
// ...]
//
// --calibrate writes the budget planner's calibration table (tools/calibrate.hpp); with scene
// files it measures those instead of the calibration set (the Pareto plot's figures).
//
// For each value of the swept setting: bake time, the median frame time over --frames renders,
// and the relative RMSE against a reference image of the same term over the pixels the medium
// covers. The reference is rendered once by the `reference` pipeline (marched for the single
// term, else Monte Carlo at --reference-spp) and kept at --reference (default: beside the CSV);
// its own noise level is reported so that nobody reads noise as error.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "core/errors.hpp"
#include "pipelines/budget/planner.hpp"
#include "pipelines/metrics.hpp"
#include "pipelines/pipeline.hpp"
#include "tools/calibrate.hpp"
#include "tools/commands.hpp"
#include "tools/settings_option.hpp"

namespace scatter::tools {
namespace {

struct BenchOptions {
  std::string scene, pipeline, terms = "all", sweep, reference, csv, device;
  std::vector<std::string> settings;
  int reference_spp = 1024, frames = 3, width = 0, height = 0;
  double max_error = 0;  // 0: none
};

struct Sweep {
  std::string key;
  std::vector<double> values;
};

Sweep parse_sweep(const std::string& text) {
  auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ValidationError("--sweep", "expects key=v1,v2,..., got \"" + text + "\"");
  Sweep s{text.substr(0, eq), {}};
  for (const auto& [k, v] : parse_settings({s.key + "=0"})) (void)k, (void)v;  // key syntax
  std::string rest = text.substr(eq + 1);
  size_t start = 0;
  while (start <= rest.size()) {
    size_t comma = rest.find(',', start);
    std::string item =
        rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    s.values.push_back(parse_settings({s.key + "=" + item}).at(s.key));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return s;
}

struct Reference {
  Image image;
  double noise = 0;  // relative norm of its standard error (0 when deterministic)
};

std::filesystem::path std_error_file(std::filesystem::path p) {
  auto ext = p.extension().string();
  return p.replace_extension(".stderr" + ext);
}

Reference load_or_render_reference(const BenchOptions& o, const Scene& scene, Terms terms,
                                   gpu::Gpu& gpu, const std::vector<uint8_t>& mask) {
  Reference ref;
  std::filesystem::path path = o.reference;
  if (std::filesystem::exists(path)) {
    ref.image = read_image(path);
    if (ref.image.width != scene.width || ref.image.height != scene.height)
      throw ValidationError("--reference",
                            path.string() + " is " + std::to_string(ref.image.width) + "x" +
                                std::to_string(ref.image.height) + ", the scene renders " +
                                std::to_string(scene.width) + "x" + std::to_string(scene.height));
    if (std::filesystem::exists(std_error_file(path)))
      ref.noise = relative_norm(read_image(std_error_file(path)), ref.image, mask);
    spdlog::info("reference {} (noise {:.3g})", path.string(), ref.noise);
    return ref;
  }
  auto pipeline = make_pipeline("reference", gpu);
  RenderRequest request{terms, {}, nullptr};
  if (terms == Terms::Single) {
    request.settings["step"] = 0.125;
  } else {
    request.settings["spp"] = o.reference_spp;
    request.settings["seed"] =
        7919;  // not the swept renders' seed: their noise must be independent
  }
  std::cerr << "bench: rendering the reference " << path.string() << " ...\n";
  RenderResult r = pipeline->render(scene, request);
  if (!path.parent_path().empty()) std::filesystem::create_directories(path.parent_path());
  write_image(r.image, path);
  if (r.std_error) {
    write_image(*r.std_error, std_error_file(path));
    ref.noise = relative_norm(*r.std_error, r.image, mask);
  }
  ref.image = std::move(r.image);
  return ref;
}

int run_bench(BenchOptions o) {
  for (auto [value, name] : {std::pair{&o.pipeline, "--pipeline"},
                             {&o.sweep, "--sweep"},
                             {&o.csv, "--csv"},
                             {&o.scene, "scene"}})
    if (value->empty()) throw ValidationError(name, "is required (or give --calibrate)");
  Scene scene = load_scene(o.scene);
  if (o.width) scene.width = o.width;
  if (o.height) scene.height = o.height;
  Terms terms = parse_terms(o.terms);
  Sweep sweep = parse_sweep(o.sweep);
  Settings base = parse_settings(o.settings);
  if (o.frames < 1 || o.frames > 1000) throw ValidationError("--frames", "must be in [1, 1000]");
  if (o.max_error != 0) check_budget(o.pipeline, o.max_error, "--max-error");
  if (o.reference.empty()) {
    // Named by everything the reference depends on, so a changed scene or setting never reuses
    // a stale file: the scene file's text, the terms, the size, the sample count and the version
    // of the reference code (bump kReferenceVersion when its results change).
    constexpr const char* kReferenceVersion = "2";
    std::ifstream in(o.scene);
    std::string key((std::istreambuf_iterator<char>(in)), {});
    key += "|" + o.terms + "|" + std::to_string(scene.width) + "x" + std::to_string(scene.height) +
           "|" + std::to_string(o.reference_spp) + "|" + kReferenceVersion;
    char hash[17];
    std::snprintf(hash, sizeof hash, "%016zx", std::hash<std::string>{}(key));
    auto stem = std::filesystem::path(o.scene).stem().string();
    o.reference = (std::filesystem::path(o.csv).parent_path() /
                   (stem + "." + o.terms + "." + hash + ".reference.exr"))
                      .string();
  }
  gpu::Gpu gpu(gpu::GpuOptions{o.device});
  auto pipeline = make_pipeline(o.pipeline, gpu);
  auto mask = coverage_mask(scene, voxelize(scene, {.resolution = scene.voxels}));
  Reference ref = load_or_render_reference(o, scene, terms, gpu, mask);

  std::ofstream csv(o.csv);
  if (!csv) throw std::runtime_error("cannot write " + o.csv);
  csv << "pipeline,scene,terms,width,height,key,value,bake_ms,frame_ms_median,frames,rel_rmse,"
         "reference_noise,stage_ms_median,error_estimate\n";
  for (double v : sweep.values) {
    RenderRequest request{terms, base, nullptr};
    request.settings[sweep.key] = v;
    if (o.max_error != 0) request.max_error = o.max_error;
    auto t0 = std::chrono::steady_clock::now();
    pipeline->bake(scene, request);
    double bake_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::vector<double> times;
    std::map<std::string, std::vector<double>> stages;  // first-seen order kept in `order`
    std::vector<std::string> order;
    RenderResult last;
    for (int f = 0; f < o.frames; ++f) {
      auto s = std::chrono::steady_clock::now();
      last = pipeline->render(scene, request);
      times.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - s).count());
      for (const auto& st : last.timings) {
        if (!stages.count(st.stage)) order.push_back(st.stage);
        stages[st.stage].push_back(st.ms);
      }
    }
    std::string stage_ms;  // "stage:median;..." (a stage's median over the frames that ran it)
    for (const auto& name : order) {
      auto& ms = stages[name];
      std::sort(ms.begin(), ms.end());
      std::ostringstream item;
      item << name << ":" << ms[ms.size() / 2];
      stage_ms += (stage_ms.empty() ? "" : ";") + item.str();
    }
    std::sort(times.begin(), times.end());
    double median = times[times.size() / 2];
    double err = relative_rmse(last.image, ref.image, mask);
    csv << (o.pipeline == "auto" ? last.plan.pipeline : o.pipeline) << ","
        << std::filesystem::path(o.scene).stem().string() << "," << o.terms << "," << scene.width
        << "," << scene.height << "," << sweep.key << "," << v << "," << bake_ms << "," << median
        << "," << o.frames << "," << err << "," << ref.noise << "," << stage_ms << ","
        << (last.error_estimate ? (std::ostringstream() << *last.error_estimate).str() : "")
        << "\n";
    std::cout << o.pipeline << " " << sweep.key << "=" << v << ": frame " << median
              << " ms (median of " << o.frames << "), relative RMSE " << err << " (reference noise "
              << ref.noise << ")" << std::endl;
  }
  return 0;
}

}  // namespace

Handler add_bench_command(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  auto c = std::make_shared<CalibrateOptions>();
  auto files = std::make_shared<std::vector<std::string>>();
  CLI::App* cmd = app.add_subcommand("bench", "Frame time against error, over a swept setting");
  cmd->add_option("scene", *files, "Scene JSON file (with --calibrate: any number)");
  cmd->add_option("--pipeline", o->pipeline, "Pipeline name");
  cmd->add_option("--terms", o->terms, "surface, single, multiple or all")->capture_default_str();
  cmd->add_option("--sweep", o->sweep, "key=v1,v2,...: the setting to vary");
  cmd->add_option("--set", o->settings, "Fixed setting key=value (repeatable)");
  cmd->add_option("--reference", o->reference,
                  "Reference EXR: read if it exists, else rendered there");
  cmd->add_option("--reference-spp", o->reference_spp,
                  "Samples per pixel of a Monte Carlo reference")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Renders per setting; the median time is reported")
      ->capture_default_str();
  cmd->add_option("--width", o->width, "Override the scene's image width");
  cmd->add_option("--height", o->height, "Override the scene's image height");
  cmd->add_option("--device", o->device, "OpenCL device: P:D or part of its name");
  cmd->add_option("--csv", o->csv, "Output CSV");
  cmd->add_option("--max-error", o->max_error, "The budget auto plans by (a relative RMSE)");
  cmd->add_option("--calibrate", c->out,
                  "Write the budget planner's calibration table here (its version + 1)");
  cmd->add_flag("--quick", c->quick, "--calibrate: two scenes, to try it");
  cmd->add_flag("--reuse", c->reuse,
                "--calibrate: keep the rows of the scenes the table already holds (by name), "
                "render only the others");
  cmd->add_option("--size", c->size, "--calibrate: image side")->capture_default_str();
  cmd->add_option("--voxels", c->voxels, "--calibrate: voxels on the long side")
      ->capture_default_str();
  cmd->add_option("--max-spp", c->max_spp, "--calibrate: the references' samples, at most")
      ->capture_default_str();
  return [o, c, files] {
    if (!c->out.empty()) {
      c->scenes = *files;
      c->device = o->device;
      return run_calibration(*c);
    }
    if (files->size() > 1) throw ValidationError("scene", "one scene file (or give --calibrate)");
    if (!files->empty()) o->scene = files->front();
    return run_bench(*o);
  };
}

}  // namespace scatter::tools
