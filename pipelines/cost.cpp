#include "pipelines/cost.hpp"

#include "core/errors.hpp"
#include "pipelines/auto_pipeline.hpp"
#include "pipelines/lbl/lbl_pipeline.hpp"
#include "pipelines/psf/psf_pipeline.hpp"
#include "pipelines/reference/reference_pipeline.hpp"
#include "pipelines/single/single_pipeline.hpp"
#include "pipelines/surface/surface_pipeline.hpp"
#include "pipelines/thickness/thickness_pipeline.hpp"

namespace scatter {

CostEstimate estimate_cost(const std::string& pipeline, const Scene& scene,
                           const RenderRequest& request, bool bake) {
  if (pipeline == "auto") {
    // AutoPipeline::render delegates to its choice with the same request; it bakes nothing.
    CostEstimate e =
        estimate_cost(AutoPipeline::choose(scene, request.terms).first, scene, request, bake);
    e.summary = "auto -> " + e.summary;
    return e;
  }
  if (pipeline == "surface") return SurfacePipeline::estimate(scene, request, bake);
  if (pipeline == "reference") return ReferencePipeline::estimate(scene, request, bake);
  if (pipeline == "thickness") return ThicknessPipeline::estimate(scene, request, bake);
  if (pipeline == "single") return SinglePipeline::estimate(scene, request, bake);
  if (pipeline == "lbl") return LblPipeline::estimate(scene, request, bake);
  if (pipeline == "psf") return PsfPipeline::estimate(scene, request, bake);
  throw ValidationError("pipeline", "unknown pipeline \"" + pipeline + "\"");
}

}  // namespace scatter
