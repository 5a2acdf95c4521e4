// What a render or bake will cost before it runs: host and device memory and seconds on this
// machine's 2-core CPU (PoCL / llvmpipe), from the scene and the request's settings alone. The
// daemon compares these against --max-request-mb and --max-render-s and refuses a request past
// them, naming the field that drives the cost.
//
// Each estimate counts the pipeline's own allocations (host std::vectors, cl::Buffers, GL
// textures and buffers; on a CPU device the device's bytes are host memory too) at their peak,
// with the allocation sites cited beside the formulas in pipelines/*/..._cost.cpp. Time is a
// count of work units times a per-unit constant measured here, rounded up (conservative).
#pragma once

#include <string>

#include "pipelines/pipeline.hpp"
#include "scene/scene.hpp"

namespace scatter {

struct CostEstimate {
  double host_bytes = 0;    // peak host memory of this render or bake, beyond the loaded scene
  double device_bytes = 0;  // OpenCL buffers and GL textures/renderbuffers it allocates
  double seconds = 0;       // expected run time on a 2-core CPU (PoCL/llvmpipe); conservative
  // Of `seconds`, what a pipeline that keeps state between frames skips while it is kept
  // (Pipeline::keeps; lbl: volume, march and diffusion); 0 for the others.
  double kept_seconds = 0;
  std::string memory_field;  // the request field that drives memory most ("scene.voxels", ...)
  std::string time_field;    // the field that drives time most ("settings.spp", ...)
  std::string summary;       // one line a person can act on: "514^3 voxels x 89 B = 12 GB"

  double bytes() const { return host_bytes + device_bytes; }
};

// What rendering (bake = false) or baking (bake = true) `scene` with `pipeline` and `request`
// will cost. Allocates nothing it estimates, takes well under a millisecond (the mesh's bounds
// are its largest loop), needs no GPU context and no pipeline instance. `auto` estimates the
// pipeline AutoPipeline::choose() picks. A render of a pipeline that bakes (single) includes the
// bake, since a render on a cache miss bakes first. Throws ValidationError for an unknown
// pipeline or a setting the pipeline rejects (the same message render() would give).
CostEstimate estimate_cost(const std::string& pipeline, const Scene& scene,
                           const RenderRequest& request, bool bake = false);

}  // namespace scatter
