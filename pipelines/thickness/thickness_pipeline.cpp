#include "pipelines/thickness/thickness_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "bake/cache.hpp"
#include "core/errors.hpp"
#include "pipelines/common/raster.hpp"
#include "pipelines/common/stage_clock.hpp"
#include "scene/mesh.hpp"

namespace scatter {

namespace {
constexpr double kPieceStepsPerBand = 512.0 * 512 * 32 / 4;
}  // namespace

Plan ThicknessPipeline::plan(const Scene& scene, const RenderRequest& request) {
  require_terms(*this, request.terms);
  return describe(scene, request.terms, ThicknessSettings::read(request.settings));
}

Plan ThicknessPipeline::describe(const Scene& scene, Terms terms,
                                 const ThicknessSettings& s) const {
  if (!scene.medium.density->homogeneous())
    throw ValidationError("scene.medium.density",
                          "the thickness pipeline needs a homogeneous "
                          "medium (constant density); use reference");
  Plan p{name(), terms, {}};
  p.stages.push_back({"bake", false, "homogeneous medium: no optical-depth bake is needed"});
  const std::string maps = std::to_string(scene.lights.size()) + " lights, " +
                           std::to_string(s.shadow_size) + "^2 distance maps";
  if (kept_shadows(shadows_key(scene, s)))
    p.stages.push_back({"shadow_maps", false, "kept: " + maps + " of the same mesh and lights"});
  else
    p.stages.push_back({"shadow_maps", !scene.lights.empty(), maps});
  p.stages.push_back({"depth_peel", true, "front and second surface along each view ray"});
  p.stages.push_back({"integrate", true, std::to_string(s.steps) + " pieces per view segment"});
  if (scene.medium.ior != 1.0)
    p.stages.push_back(
        {"boundary", false,
         "refraction and Fresnel are neglected (ior " + std::to_string(scene.medium.ior) + ")"});
  p.stages.push_back({"readback", true, "linear RGB to the host"});
  return p;
}

// What the shadow maps depend on: the mesh (its bounds place the light's frustum), each light's
// type, position and direction, and the maps' size.
std::string ThicknessPipeline::shadows_key(const Scene& scene, const ThicknessSettings& s) {
  BakeKey k;
  k.add("mesh", mesh_key(scene)).add("shadow_size", s.shadow_size);
  for (const Light& l : scene.lights) {
    k.add("type", static_cast<double>(l.type));
    for (int c = 0; c < 3; ++c) k.add("position", l.position[c]).add("direction", l.direction[c]);
  }
  return k.hex();
}

const ThicknessPipeline::Shadows* ThicknessPipeline::kept_shadows(const std::string& key) const {
  for (const Shadows& s : kept_)
    if (s.key == key) return &s;
  return nullptr;
}

const ThicknessPipeline::Shadows& ThicknessPipeline::shadows(const Scene& scene,
                                                             const ThicknessSettings& s,
                                                             const MeshBuffers& mesh) {
  std::string key = shadows_key(scene, s);
  for (auto it = kept_.begin(); it != kept_.end(); ++it)
    if (it->key == key) {
      kept_.splice(kept_.begin(), kept_, it);
      return kept_.front();
    }
  // One distance map per light, seen from the light.
  Shadows made{std::move(key), {}, {}};
  for (const Light& l : scene.lights) {
    LightView v = light_view(l, scene, "thickness");
    made.maps.push_back(std::make_unique<RenderTarget>(s.shadow_size, s.shadow_size));
    draw_distance(distance_program_.get(), mesh, *made.maps.back(), v.view, v.projection, v.origin,
                  v.direction, v.along_direction, 0,
                  1e30f);  // off the object: no medium on the way
    made.light_matrices.push_back(v.projection * v.view);
  }
  glFinish();
  if (kept_.size() >= kKeptShadowSets) kept_.pop_back();
  kept_.push_front(std::move(made));
  return kept_.front();
}

RenderResult ThicknessPipeline::render(const Scene& scene, const RenderRequest& request) {
  RenderResult result;
  require_terms(*this, request.terms);
  const ThicknessSettings s = ThicknessSettings::read(request.settings);  // once a frame
  result.plan = describe(scene, request.terms, s);
  gpu_.gl().make_current();
  if (!distance_program_) {
    distance_program_ = build_distance_program();
    integrate_program_ =
        gpu::build_program("shaders/common/fullscreen.vert", "shaders/thickness/integrate.frag");
    empty_vao_ = gpu::GlObject::create(gpu::GlKind::VertexArray);
  }
  StageClock clock(result.timings);
  const MeshBuffers& mesh = mesh_.get(scene);
  const GLuint dist = distance_program_.get(), integ = integrate_program_.get();
  const bool kept = kept_shadows(shadows_key(scene, s)) != nullptr;
  const Shadows& sh = shadows(scene, s, mesh);
  const auto& shadow_maps = sh.maps;
  const auto& light_matrices = sh.light_matrices;
  if (!kept) clock.stop("shadow_maps");

  // Depth peeling from the camera: the first surface, then the next one behind it.
  CameraMatrices cam = camera_matrices(scene);
  const Vec3& eye = scene.camera.position;
  RenderTarget front(scene.width, scene.height), back(scene.width, scene.height);
  draw_distance(dist, mesh, front, cam.view, cam.projection, eye, Vec3{}, false, 0);
  draw_distance(dist, mesh, back, cam.view, cam.projection, eye, Vec3{}, false,
                front.color_texture());
  glFinish();
  clock.stop("depth_peel");

  RenderTarget out(scene.width, scene.height);
  set_light_uniforms(integ, scene.lights);
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const Light& l = scene.lights[i];
    LightView v = light_view(l, scene, "thickness");
    glBindTextureUnit(static_cast<GLuint>(2 + i), shadow_maps[i]->color_texture());
    uniform1i(integ, indexed("shadow_maps", i), static_cast<int>(2 + i));
    uniform_matrix(integ, indexed("light_matrix", i), light_matrices[i]);
    // The distance a directional light's map stores is measured from its origin plane.
    if (l.type == Light::Type::Directional) uniform3(integ, indexed("light_position", i), v.origin);
  }
  uniform1i(integ, "front", 0);
  uniform1i(integ, "back", 1);
  const bool inside = mesh_.eye_inside(scene);
  uniform1i(integ, "eye_inside", inside ? 1 : 0);
  for (StagePlan& stage : result.plan.stages)
    if (stage.name == "depth_peel" && inside)
      stage.reason = "the eye inside the object: from the eye to the first surface along each ray";
  glBindTextureUnit(0, front.color_texture());
  glBindTextureUnit(1, back.color_texture());
  set_camera_uniforms(integ, scene);
  double density = scene.medium.density->density(Vec3{});
  uniform3(integ, "sigma_s", scene.medium.sigma_s * density);
  uniform3(integ, "sigma_t", (scene.medium.sigma_s + scene.medium.sigma_a) * density);
  glProgramUniform1f(integ, glGetUniformLocation(integ, "g"), float(scene.medium.g));
  uniform1i(integ, "steps", s.steps);
  out.bind_and_clear(scene.background);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(integ);
  glBindVertexArray(empty_vao_.get());
  // The GL state back as the other draws expect it, also when a progress stops the frame.
  const auto unbind = [&, units = GLuint(2 + scene.lights.size())] {
    glDisable(GL_SCISSOR_TEST);
    glBindVertexArray(0);
    glUseProgram(0);
    for (GLuint unit = 0; unit < units; ++unit) glBindTextureUnit(unit, 0);
  };
  // In bands of rows where a progress can stop it (the high step takes seconds on a loaded CPU):
  // a live view's pose waits for a band, not for the whole integral. A band is about
  // kPieceStepsPerBand pixel pieces (25 ms on this CPU idle), so a small frame is one draw.
  const double pieces = double(scene.width) * scene.height * s.steps;
  const int bands = std::clamp(int(std::ceil(pieces / kPieceStepsPerBand)), 1, 16);
  if (request.progress && bands > 1) {
    const int band = std::max(8, (scene.height + bands - 1) / bands);
    glEnable(GL_SCISSOR_TEST);
    try {
      for (int y = 0; y < scene.height; y += band) {
        const int rows = std::min(band, scene.height - y);
        glScissor(0, y, scene.width, rows);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        request.progress(double(y + rows) / scene.height);
      }
    } catch (...) {
      unbind();
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      throw;
    }
  } else {
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  unbind();
  gpu::check_gl("thickness integrate");
  glFinish();
  clock.stop("integrate");

  result.image = out.read_color();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  clock.stop("readback");
  return result;
}

}  // namespace scatter
