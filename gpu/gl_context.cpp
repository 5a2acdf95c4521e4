#include "gpu/gl_context.hpp"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <vector>

namespace scatter::gpu {
namespace {

std::string egl_error() {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04x", eglGetError());
  return buf;
}

// Tries the platforms a headless machine may offer, in order, and initialises the first that works.
EGLDisplay open_display(std::string& platform) {
  if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
      platform = "surfaceless";
      return d;
    }
  }
  if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[8];
    EGLint count = 0;
    if (eglQueryDevicesEXT(8, devices, &count))
      for (EGLint i = 0; i < count; ++i) {
        EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
          platform = "device";
          return d;
        }
      }
  }
  EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
    platform = "default";
    return d;
  }
  throw GpuError("no EGL display available (" + egl_error() +
                 "): install Mesa's EGL (libegl-mesa0, libgl1-mesa-dri) or a GPU driver");
}

}  // namespace

GlContext::GlContext() {
  EGLDisplay display = open_display(platform_);
  display_ = display;
  try {
    if (!eglBindAPI(EGL_OPENGL_API))
      throw GpuError("EGL cannot bind the OpenGL API (" + egl_error() + ")");
    const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint n = 0;
    if (!eglChooseConfig(display, config_attribs, &config, 1, &n) || n == 0) {
      if (!epoxy_has_egl_extension(display, "EGL_KHR_no_config_context"))
        throw GpuError("EGL offers no OpenGL-capable config");
      config = EGL_NO_CONFIG_KHR;
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                      4,
                                      EGL_CONTEXT_MINOR_VERSION,
                                      5,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
    if (ctx == EGL_NO_CONTEXT)
      throw GpuError("the EGL driver cannot create an OpenGL 4.5 core context (" + egl_error() +
                     ")");
    context_ = ctx;
    make_current();
    auto text = [](GLenum name) {
      const GLubyte* s = glGetString(name);
      return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("unknown");
    };
    renderer_ = text(GL_RENDERER);
    version_ = text(GL_VERSION);
  } catch (...) {
    if (context_) eglDestroyContext(display, context_);
    throw;
  }
}

// The display is never terminated: EGL hands the same display to every caller in the process, so
// terminating it would invalidate every other context on it. It is released at exit.
GlContext::~GlContext() {
  if (eglGetCurrentContext() == context_)
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
}

void GlContext::make_current() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    throw GpuError("cannot make the OpenGL context current without a surface (" + egl_error() +
                   ")");
}

}  // namespace scatter::gpu
