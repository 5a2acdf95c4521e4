// What a bake reports: the result a pipeline's bake() returns and a bake job keeps, and the
// progress callback it calls. Below pipelines/: bake/jobs.hpp and the pipelines both use it.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace scatter {

// Wall-clock milliseconds of one stage (of a bake or a render).
struct StageTime {
  std::string stage;
  double ms = 0;
};

struct BakeResult {
  bool needed = false;                  // false: this pipeline bakes nothing
  bool cache_hit = false;               // the product came from the cache (memory or disk)
  std::string key;                      // content address of the product
  std::vector<StageTime> timings;       // this call's stages (a hit: the lookup only)
  std::vector<StageTime> bake_timings;  // the stages of the bake that made the product
  nlohmann::json stats;                 // pipeline-specific facts about the product
};

// Reports progress of a bake: stage name and the fraction of that stage done.
using BakeProgress = std::function<void(const std::string& stage, double fraction)>;

}  // namespace scatter
