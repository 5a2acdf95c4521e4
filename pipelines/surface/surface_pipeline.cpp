#include "pipelines/surface/surface_pipeline.hpp"

#include "pipelines/stage_clock.hpp"
#include "pipelines/surface/raster.hpp"

namespace scatter {
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
