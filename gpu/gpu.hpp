// The GPU contexts a render thread owns, created on first use so that a pipeline that needs only
// OpenGL runs on a machine without OpenCL and the other way round.
#pragma once

#include <memory>
#include <string>

#include "core/errors.hpp"
#include "gpu/cl_context.hpp"
#include "gpu/gl_context.hpp"

namespace scatter::gpu {

struct GpuOptions {
  std::string cl_device;  // ClContext selector; "" = first GPU, else first device
  // When not empty, cl() and gl() throw GpuError with this text instead of making a context: a
  // Gpu for code that must not touch the device (tests of plan(), validation at the edge).
  std::string unavailable;
};

class Gpu {
 public:
  explicit Gpu(GpuOptions options = {}) : options_(std::move(options)) {}
  ClContext& cl() {
    if (!options_.unavailable.empty()) throw GpuError(options_.unavailable);
    if (!cl_) cl_ = std::make_unique<ClContext>(options_.cl_device);
    return *cl_;
  }
  GlContext& gl() {
    if (!options_.unavailable.empty()) throw GpuError(options_.unavailable);
    if (!gl_) gl_ = std::make_unique<GlContext>();
    return *gl_;
  }

 private:
  GpuOptions options_;
  std::unique_ptr<ClContext> cl_;
  std::unique_ptr<GlContext> gl_;
};

}  // namespace scatter::gpu
