// The interface every rendering pipeline implements, and the factory that makes one by name.
//
//   plan(scene, request)   which stages this scene and request need, and why others are skipped
//   bake(scene, request)   cacheable per-asset products (none for pipelines that need no bake)
//   render(scene, request) linear float RGB holding the requested light-transport terms,
//                          with the plan it followed and milliseconds per stage
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bake/bake_result.hpp"
#include "gpu/gpu.hpp"
#include "pipelines/image.hpp"
#include "scene/scene.hpp"

namespace scatter {

// Which light-transport terms an image holds.
enum class Terms { Surface, Single, Multiple, All };
std::string to_string(Terms t);
// Throws ValidationError for anything but surface, single, multiple, all.
Terms parse_terms(const std::string& s);

struct StagePlan {
  std::string name;
  bool run = true;
  std::string reason;  // why it runs or why it is skipped
};

// Numeric knobs a pipeline understands ("spp", "step", ...); each pipeline documents its own and
// rejects the ones it does not know, so a typo is an error rather than a silent default.
using Settings = std::map<std::string, double>;

// One way of rendering a request that a budget planner (auto with quality.max_error) weighed:
// a pipeline (or "single-from+multiple-from" for a composite) and its settings, with the error
// against the reference of the requested terms (relative RMSE) and the seconds it expects.
struct PlanOption {
  std::string pipeline;
  Settings settings;
  double expected_error = 0;
  double expected_seconds = 0;
  std::string note;  // why it was or was not chosen
};

struct Plan {
  std::string pipeline;
  Terms terms = Terms::All;
  std::vector<StagePlan> stages;
  // Set by a planner: what the chosen way expects, and the others it weighed.
  std::optional<double> expected_error, expected_seconds;
  std::vector<PlanOption> alternatives;
};

// The stage called `name`; throws std::logic_error when the plan has none (a pipeline's bug).
StagePlan& plan_stage(Plan& plan, const std::string& name);

struct RenderRequest {
  Terms terms = Terms::All;
  Settings settings;
  // Called now and then with the fraction done, for long renders.
  std::function<void(double)> progress;
  // The error the caller accepts (relative RMSE against the reference of `terms`, e.g. 0.05):
  // auto plans by it, the reference takes as many samples as it needs; other pipelines reject it.
  std::optional<double> max_error;
  // The path tracer samples until its relative standard error is under this fraction of
  // max_error: one image's error scatters about its standard error (a 24 x 24 sphere at g -0.5
  // and -0.9, budgets 10 and 20 %, three seeds each: 0.97-1.06x it), and stopping at the budget
  // itself left 7 of 31 budget runs off the calibration grid over it (docs/BENCHMARKS.md).
  static constexpr double kBudgetMargin = 0.9;
  // max_error is auto's own aim (none was asked for), not the caller's: the path tracer samples
  // towards it only as far as the calibrated count, 8x (no further on its measured error).
  bool soft_budget = false;
  // > 0: the caller cancels the render this many seconds after `started` (the daemon's
  // --max-render-s); work that can stop early (the path tracer's passes) stops in time to
  // return what it has. `started`: when the request was made, unless the caller says otherwise.
  double time_limit_s = 0;
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
};

struct RenderResult {
  Image image;
  std::optional<Image> std_error;  // per-pixel standard error, for Monte Carlo estimates
  // This image's estimated error against the reference of its terms (relative RMSE): from
  // std_error for Monte Carlo estimates, from the calibration table for the approximations.
  std::optional<double> error_estimate;
  Plan plan;
  std::vector<StageTime> timings;
};

// Reads Settings with defaults and ranges; finish() rejects keys nobody read.
class SettingsReader {
 public:
  SettingsReader(const Settings& settings, std::string pipeline)
      : settings_(settings), pipeline_(std::move(pipeline)) {}
  double number(const std::string& key, double fallback, double lo, double hi);
  int integer(const std::string& key, int fallback, int lo, int hi);
  void finish() const;

 private:
  const Settings& settings_;
  std::string pipeline_;
  std::set<std::string> used_;
};

class BakeCache;

void to_json(nlohmann::json& j, const StagePlan& s);
void to_json(nlohmann::json& j, const PlanOption& o);
void to_json(nlohmann::json& j, const Plan& p);

struct PipelineInfo;  // pipelines/registry.hpp

class Pipeline {
 public:
  virtual ~Pipeline() = default;
  // The pipeline's description in the registry: name, terms, settings, bake stages.
  virtual const PipelineInfo& info() const = 0;
  std::string name() const;
  // The terms this pipeline can render; render() rejects others with a ValidationError.
  std::vector<Terms> supported_terms() const;
  // The stages bake() reports progress for, each with its rough share of the whole bake.
  std::vector<std::pair<std::string, double>> bake_stages() const;
  virtual Plan plan(const Scene& scene, const RenderRequest& request) = 0;
  // Makes (or finds in the cache) what render() will need for this scene and request's settings.
  virtual BakeResult bake(const Scene&, const RenderRequest&, const BakeProgress& = {}) {
    return {};
  }
  virtual RenderResult render(const Scene& scene, const RenderRequest& request) = 0;
  // Whether this instance still holds what a frame of `scene` for `request` builds before its
  // last pass (lbl: the volume, the deposit and the converged lattice), so that the frame costs
  // only that pass (CostEstimate::kept_seconds is the rest). Planners ask it; false by default.
  virtual bool keeps(const Scene&, const RenderRequest&) const { return false; }
};

// Names the registry holds (pipelines/registry.hpp), in a stable order.
std::vector<std::string> pipeline_names();
// Throws ValidationError (field "pipeline") for an unknown name. Pipelines that bake keep their
// products in `cache` (shared, content-addressed); without one they keep a private memory cache.
std::unique_ptr<Pipeline> make_pipeline(const std::string& name, gpu::Gpu& gpu,
                                        BakeCache* cache = nullptr);

// v with 3 significant digits, for plan reasons ("0.05", "1e+03").
std::string short_number(double v);
// v's shortest text that reads back to the same double, for keys.
std::string exact_number(double v);

// Throws ValidationError unless `pipeline` supports `terms`.
void require_terms(const Pipeline& pipeline, Terms terms);

}  // namespace scatter
