// A headless OpenGL 4.5 core context through EGL: the surfaceless platform (Mesa), else an EGL
// device (NVIDIA), else the default display. No window system is needed.
#pragma once

#include <string>

#include "core/errors.hpp"

namespace scatter::gpu {

class GlContext {
 public:
  // Creates the context and makes it current on the calling thread; throws GpuError if EGL has no
  // display or the driver cannot give OpenGL 4.5 core.
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // Makes the context current on the calling thread (the render thread owns it).
  void make_current();
  const std::string& renderer() const { return renderer_; }
  const std::string& version() const { return version_; }
  const std::string& platform() const { return platform_; }

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string renderer_, version_, platform_;
};

}  // namespace scatter::gpu
