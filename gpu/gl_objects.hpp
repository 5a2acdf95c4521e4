// Move-only owners of OpenGL object names, so that no GL object outlives its owner or leaks on an
// exception. The GL context must be current on the thread that destroys them.
#pragma once

#include <epoxy/gl.h>

#include <string>
#include <utility>

namespace scatter::gpu {

enum class GlKind { Buffer, Texture, Framebuffer, VertexArray, Program, Shader };

class GlObject {
 public:
  GlObject() = default;
  GlObject(GlKind kind, GLuint name) : kind_(kind), name_(name) {}
  static GlObject create(GlKind kind, GLenum shader_type = 0);
  ~GlObject() { reset(); }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  GlObject(GlObject&& o) noexcept : kind_(o.kind_), name_(std::exchange(o.name_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    if (this != &o) {
      reset();
      kind_ = o.kind_;
      name_ = std::exchange(o.name_, 0);
    }
    return *this;
  }

  GLuint get() const { return name_; }
  explicit operator bool() const { return name_ != 0; }
  void reset();

 private:
  GlKind kind_ = GlKind::Buffer;
  GLuint name_ = 0;
};

// Compiles and links a vertex + fragment shader pair from shaders/; throws GpuError with the info
// log of the stage that failed. `defines` ("#define NAME 1\n" lines) go after each stage's
// #version line: a variant of the same sources.
GlObject build_program(const std::string& vertex_path, const std::string& fragment_path,
                       const std::string& defines = "");
// Compiles and links a compute shader from shaders/.
GlObject build_compute_program(const std::string& path);

// Throws GpuError naming `what` if glGetError reports an error.
void check_gl(const char* what);

}  // namespace scatter::gpu
