#include "pipelines/surface/surface_pipeline.hpp"

#include <memory>

#include "pipelines/common/raster.hpp"
#include "pipelines/common/stage_clock.hpp"

namespace scatter {

Plan SurfacePipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  return describe(scene, request.terms, SurfaceSettings::read(request.settings));
}

Plan SurfacePipeline::describe(const Scene& scene, Terms terms, const SurfaceSettings& s) const {
  Plan p{name(), terms, {}};
  p.stages.push_back({"upload", true, std::to_string(scene.mesh->triangle_count()) + " triangles"});
  p.stages.push_back({"shadow_maps", s.shadows && !scene.lights.empty(),
                      s.shadows
                          ? std::to_string(s.shadow_size) + "^2 distance map per light"
                          : "shadows off (settings.shadows 0): every facet facing a light is lit"});
  p.stages.push_back({"raster", true,
                      scene.lights.empty() ? "no lights: the mesh renders black"
                                           : std::to_string(scene.lights.size()) + " lights"});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

RenderResult SurfacePipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  const SurfaceSettings s = SurfaceSettings::read(request.settings);  // once a frame
  result.plan = describe(scene, request.terms, s);
  gpu_.gl().make_current();
  if (!program_)
    program_ = gpu::build_program("shaders/surface/mesh.vert", "shaders/surface/blinn_phong.frag");
  StageClock clock(result.timings);
  MeshBuffers mesh(*scene.mesh);
  RenderTarget target(scene.width, scene.height);
  glFinish();
  clock.stop("upload");

  GLuint prog = program_.get();
  std::vector<std::unique_ptr<RenderTarget>> maps;
  glProgramUniform1i(prog, glGetUniformLocation(prog, "shadowed"), s.shadows ? 1 : 0);
  if (s.shadows) {
    if (!distance_program_) distance_program_ = build_distance_program();
    Aabb b = scene.mesh->bounds();
    // A texel's footprint at the far side of the object, so a lit surface does not shadow itself.
    float bias = static_cast<float>(2.5 * length(b.size()) / s.shadow_size);
    glProgramUniform1f(prog, glGetUniformLocation(prog, "shadow_bias"), bias);
    for (size_t i = 0; i < scene.lights.size(); ++i) {
      LightView v = light_view(scene.lights[i], scene, "surface");
      maps.push_back(std::make_unique<RenderTarget>(s.shadow_size, s.shadow_size));
      draw_distance(distance_program_.get(), mesh, *maps.back(), v.view, v.projection, v.origin,
                    v.direction, v.along_direction, 0, 1e30f);
      glBindTextureUnit(static_cast<GLuint>(i), maps.back()->color_texture());
      std::string at = "[";  // (not "[" + ...: gcc 12's -Wrestrict false positive)
      at += std::to_string(i);
      at += "]";
      glProgramUniform1i(prog, glGetUniformLocation(prog, ("shadow_maps" + at).c_str()),
                         static_cast<int>(i));
      uniform_matrix(prog, "light_matrix" + at, v.projection * v.view);
      uniform3(prog, "shadow_origin" + at, v.origin);
      glProgramUniform1i(prog, glGetUniformLocation(prog, ("shadow_along" + at).c_str()),
                         v.along_direction ? 1 : 0);
    }
    glFinish();
    clock.stop("shadow_maps");
  }

  CameraMatrices cam = camera_matrices(scene);
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, "view"), 1, GL_FALSE,
                            cam.view.m.data());
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, "projection"), 1, GL_FALSE,
                            cam.projection.m.data());
  const Vec3& e = scene.camera.position;
  glProgramUniform3f(prog, glGetUniformLocation(prog, "eye"), float(e.x), float(e.y), float(e.z));
  const SurfaceMaterial& m = scene.surface;
  glProgramUniform3f(prog, glGetUniformLocation(prog, "kd"), float(m.diffuse.x), float(m.diffuse.y),
                     float(m.diffuse.z));
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
  for (size_t i = 0; i < maps.size(); ++i) glBindTextureUnit(static_cast<GLuint>(i), 0);
  gpu::check_gl("surface raster");
  glFinish();
  clock.stop("raster");

  result.image = target.read_color();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  clock.stop("readback");
  return result;
}

}  // namespace scatter
