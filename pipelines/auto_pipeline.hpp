// `auto`: picks the cheapest pipeline that can render the scene and the requested terms, and says
// why in the plan's first stage; the chosen pipeline's stages follow.
//
//   homogeneous medium, single term  -> thickness (no optical-depth bake is needed)
//   anything else                    -> reference
#pragma once

#include <map>
#include <memory>

#include "pipelines/pipeline.hpp"

namespace scatter {

class AutoPipeline : public Pipeline {
 public:
  AutoPipeline(gpu::Gpu& gpu, BakeCache* cache) : gpu_(gpu), cache_(cache) {}
  std::string name() const override { return "auto"; }
  std::vector<Terms> supported_terms() const override {
    return {Terms::Single, Terms::Multiple, Terms::All};
  }
  Plan plan(const Scene& scene, const RenderRequest& request) override;
  RenderResult render(const Scene& scene, const RenderRequest& request) override;

  // The pipeline auto would use, and why.
  static std::pair<std::string, std::string> choose(const Scene& scene, Terms terms);

 private:
  Pipeline& delegate(const std::string& name);

  gpu::Gpu& gpu_;
  BakeCache* cache_;
  std::map<std::string, std::unique_ptr<Pipeline>> pipelines_;
};

}  // namespace scatter
