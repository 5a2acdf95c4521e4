// `auto`: picks the cheapest pipeline that can render the scene and the requested terms, and says
// why in the plan's first stage; the chosen pipeline's stages follow.
//
//   homogeneous medium, single term  -> thickness (no optical-depth bake is needed)
//   anything else                    -> reference
//
// Settings: those of thickness and reference (pipelines/auto_info.cpp), each checked by its own
// pipeline whatever the choice; the chosen one gets its own.
#pragma once

#include <map>
#include <memory>

#include "pipelines/cost.hpp"
#include "pipelines/pipeline.hpp"

namespace scatter {

class AutoPipeline : public Pipeline {
 public:
  AutoPipeline(gpu::Gpu& gpu, BakeCache* cache) : gpu_(gpu), cache_(cache) {}
  const PipelineInfo& info() const override;
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

  // The pipeline auto would use, and why.
  static std::pair<std::string, std::string> choose(const Scene& scene, Terms terms);
  // The part of `settings` that `delegate` declares.
  static Settings settings_for(const std::string& delegate, const Settings& settings);
  // The cost of the chosen pipeline's render with its settings (pipelines/cost.hpp).
  static CostEstimate estimate(const Scene& scene, const RenderRequest& request, bool bake);

 private:
  Pipeline& delegate(const std::string& name);

  gpu::Gpu& gpu_;
  BakeCache* cache_;
  std::map<std::string, std::unique_ptr<Pipeline>> pipelines_;
};

}  // namespace scatter
