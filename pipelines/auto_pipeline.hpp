// `auto`: renders the requested terms within an error budget (the request's quality.max_error,
// else kDefaultMaxError) the fastest way the calibration table expects to meet it, and says in
// the plan what it chose, the error and time it expects, the alternatives it weighed and why
// (pipelines/budget/planner.hpp). A way is one pipeline at one quality, the single term from one
// pipeline plus the multiple term from another (composited: the images are summed), or the
// reference, which meets any budget.
//
// Settings: those of thickness and reference (pipelines/auto_info.cpp), each checked by its own
// pipeline whatever the choice; they override the chosen quality's for the parts that declare
// them.
#pragma once

#include <map>
#include <memory>

#include "pipelines/budget/planner.hpp"
#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter {

class AutoPipeline : public Pipeline {
 public:
  AutoPipeline(gpu::Gpu& gpu, BakeCache* cache) : gpu_(gpu), cache_(cache) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

  // What auto would do with the request (no bake counted as made when `baked` is null).
  static BudgetChoice choose(const Scene& scene, const RenderRequest& request,
                             const IsBaked& baked = nullptr);
  // The part of `settings` that `delegate` declares.
  static Settings settings_for(const std::string& delegate, const Settings& settings);
  // The cost of the chosen way (pipelines/cost.hpp): its parts' seconds summed, their largest
  // memory.
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);

 private:
  Pipeline& delegate(const std::string& name);
  // The request a part of the chosen way gets.
  static RenderRequest part_request(const BudgetChoice& c, size_t part, const RenderRequest& r);
  // The plan of choice c; `starts`, when given, gets where each part's stages begin in it.
  Plan describe(const Scene& scene, const RenderRequest& request, const BudgetChoice& c,
                std::vector<size_t>* starts = nullptr);
  // By the cache's keys, and what the delegates keep (Pipeline::keeps).
  IsBaked baked_in_cache(const Scene& scene);

  gpu::Gpu& gpu_;
  BakeCache* cache_;
  std::map<std::string, std::unique_ptr<Pipeline>> pipelines_;
};

}  // namespace scatter
