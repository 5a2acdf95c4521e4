#include "pipelines/surface/surface_pipeline.hpp"

#include <cmath>
#include <numbers>

#include "pipelines/stage_clock.hpp"
#include "pipelines/surface/raster.hpp"

namespace scatter {
namespace {

void set_light_uniforms(GLuint program, const std::vector<Light>& lights) {
  glProgramUniform1i(program, glGetUniformLocation(program, "light_count"),
                     static_cast<GLint>(lights.size()));
  for (size_t i = 0; i < lights.size(); ++i) {
    const Light& l = lights[i];
    auto loc = [&](const char* array) {
      std::string name = array;
      name.append("[").append(std::to_string(i)).append("]");
      return glGetUniformLocation(program, name.c_str());
    };
    int type = l.type == Light::Type::Point ? 0 : (l.type == Light::Type::Directional ? 1 : 2);
    Vec3 power = l.color * l.intensity;
    double to_rad = std::numbers::pi / 180;
    glProgramUniform1i(program, loc("light_type"), type);
    glProgramUniform3f(program, loc("light_position"), float(l.position.x),
                       float(l.position.y), float(l.position.z));
    glProgramUniform3f(program, loc("light_direction"), float(l.direction.x),
                       float(l.direction.y), float(l.direction.z));
    glProgramUniform3f(program, loc("light_power"), float(power.x), float(power.y),
                       float(power.z));
    glProgramUniform2f(program, loc("light_cone"), float(std::cos(l.outer_deg * to_rad)),
                       float(std::cos(l.inner_deg * to_rad)));
  }
}

}  // namespace

Plan SurfacePipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  SettingsReader(request.settings, name()).finish();  // the surface pipeline has no settings
  Plan p{name(), request.terms, {}};
  p.stages.push_back({"upload", true, std::to_string(scene.mesh.triangle_count()) + " triangles"});
  p.stages.push_back({"raster", true,
                      scene.lights.empty() ? "no lights: the mesh renders black"
                                           : std::to_string(scene.lights.size()) + " lights"});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

RenderResult SurfacePipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  result.plan = plan(scene, request);
  gpu_.gl().make_current();
  if (!program_) program_ = gpu::build_program("shaders/surface/mesh.vert", "shaders/surface/blinn_phong.frag");
  StageClock clock(result.timings);
  MeshBuffers mesh(scene.mesh);
  RenderTarget target(scene.width, scene.height);
  glFinish();
  clock.stop("upload");

  GLuint prog = program_.get();
  CameraMatrices cam = camera_matrices(scene);
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, "view"), 1, GL_FALSE, cam.view.m.data());
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, "projection"), 1, GL_FALSE,
                            cam.projection.m.data());
  const Vec3& e = scene.camera.position;
  glProgramUniform3f(prog, glGetUniformLocation(prog, "eye"), float(e.x), float(e.y), float(e.z));
  const SurfaceMaterial& m = scene.surface;
  glProgramUniform3f(prog, glGetUniformLocation(prog, "kd"), float(m.diffuse.x),
                     float(m.diffuse.y), float(m.diffuse.z));
  glProgramUniform3f(prog, glGetUniformLocation(prog, "ks"), float(m.specular.x),
                     float(m.specular.y), float(m.specular.z));
  glProgramUniform1f(prog, glGetUniformLocation(prog, "shininess"), float(m.shininess));
  set_light_uniforms(prog, scene.lights);

  target.bind_and_clear(scene.background);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glUseProgram(prog);
  mesh.draw();
  glUseProgram(0);
  gpu::check_gl("surface raster");
  glFinish();
  clock.stop("raster");

  result.image = target.read_color();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  clock.stop("readback");
  return result;
}

}  // namespace scatter
