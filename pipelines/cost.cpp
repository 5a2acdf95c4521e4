#include "pipelines/cost.hpp"

#include "pipelines/registry.hpp"

namespace scatter {

CostEstimate estimate_cost(const std::string& pipeline, const Scene& scene,
                           const RenderRequest& request, bool bake) {
  return pipeline_info(pipeline).estimate(scene, request, bake);
}

}  // namespace scatter
