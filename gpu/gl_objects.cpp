#include "gpu/gl_objects.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "core/errors.hpp"
#include "gpu/embedded_sources.hpp"

namespace scatter::gpu {

GlObject GlObject::create(GlKind kind, GLenum shader_type) {
  GLuint n = 0;
  switch (kind) {
    case GlKind::Buffer:
      glCreateBuffers(1, &n);
      break;
    case GlKind::Texture:
      glGenTextures(1, &n);
      break;
    case GlKind::Framebuffer:
      glCreateFramebuffers(1, &n);
      break;
    case GlKind::VertexArray:
      glCreateVertexArrays(1, &n);
      break;
    case GlKind::Program:
      n = glCreateProgram();
      break;
    case GlKind::Shader:
      n = glCreateShader(shader_type);
      break;
  }
  if (n == 0) throw GpuError("cannot create an OpenGL object (is a context current?)");
  return GlObject(kind, n);
}

void GlObject::reset() {
  if (name_ == 0) return;
  switch (kind_) {
    case GlKind::Buffer:
      glDeleteBuffers(1, &name_);
      break;
    case GlKind::Texture:
      glDeleteTextures(1, &name_);
      break;
    case GlKind::Framebuffer:
      glDeleteFramebuffers(1, &name_);
      break;
    case GlKind::VertexArray:
      glDeleteVertexArrays(1, &name_);
      break;
    case GlKind::Program:
      glDeleteProgram(name_);
      break;
    case GlKind::Shader:
      glDeleteShader(name_);
      break;
  }
  name_ = 0;
}

void check_gl(const char* what) {
  GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", e);
    throw GpuError(std::string("OpenGL error ") + code + " in " + what);
  }
}

namespace {

// `defines` after the source's first line (its #version).
GlObject compile(GLenum type, const std::string& path, const std::string& defines = "") {
  GlObject shader = GlObject::create(GlKind::Shader, type);
  std::string_view src = embedded_source(path);
  const size_t eol = std::min(src.find('\n'), src.size());
  const std::string_view head = src.substr(0, eol), tail = src.substr(eol);
  const std::string middle = "\n" + defines;
  const char* text[] = {head.data(), middle.data(), tail.data()};
  const GLint len[] = {static_cast<GLint>(head.size()), static_cast<GLint>(middle.size()),
                       static_cast<GLint>(tail.size())};
  glShaderSource(shader.get(), 3, text, len);
  glCompileShader(shader.get());
  GLint ok = 0;
  glGetShaderiv(shader.get(), GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(shader.get(), GL_INFO_LOG_LENGTH, &n);
    std::string log(static_cast<size_t>(std::max(n, 1)), '\0');
    glGetShaderInfoLog(shader.get(), n, nullptr, log.data());
    throw GpuError("GLSL compile of " + path + " failed:\n" + log);
  }
  return shader;
}

}  // namespace

namespace {

GlObject link(const std::vector<const GlObject*>& stages, const std::string& what) {
  GlObject program = GlObject::create(GlKind::Program);
  for (const GlObject* s : stages) glAttachShader(program.get(), s->get());
  glLinkProgram(program.get());
  GLint ok = 0;
  glGetProgramiv(program.get(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(program.get(), GL_INFO_LOG_LENGTH, &n);
    std::string log(static_cast<size_t>(std::max(n, 1)), '\0');
    glGetProgramInfoLog(program.get(), n, nullptr, log.data());
    throw GpuError("GLSL link of " + what + " failed:\n" + log);
  }
  return program;
}

}  // namespace

GlObject build_program(const std::string& vertex_path, const std::string& fragment_path,
                       const std::string& defines) {
  GlObject vs = compile(GL_VERTEX_SHADER, vertex_path, defines);
  GlObject fs = compile(GL_FRAGMENT_SHADER, fragment_path, defines);
  return link({&vs, &fs}, vertex_path + " + " + fragment_path);
}

GlObject build_compute_program(const std::string& path) {
  GlObject cs = compile(GL_COMPUTE_SHADER, path);
  return link({&cs}, path);
}

}  // namespace scatter::gpu
