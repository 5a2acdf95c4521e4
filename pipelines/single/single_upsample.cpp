// The `single` pipeline's upsample (splat_scale): the image from a splat that evaluated one pixel
// in stride x stride of it (shaders/single/upsample.frag).
#include <algorithm>

#include "pipelines/common/raster.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter {

Image SinglePipeline::upsample(const RenderTarget& splat,
                               std::array<const RenderTarget*, 4> surfaces, int stride,
                               bool clip_back, bool inside, const Scene& scene, bool per_ray) {
  if (!upsample_program_)
    upsample_program_ =
        gpu::build_program("shaders/common/fullscreen.vert", "shaders/single/upsample.frag");
  const GLuint up = upsample_program_.get();
  RenderTarget full(surfaces[0]->width(), surfaces[0]->height());
  const GLuint textures[] = {splat.color_texture(), surfaces[0]->color_texture(),
                             surfaces[1]->color_texture(), surfaces[2]->color_texture(),
                             surfaces[3]->color_texture()};
  const char* names[] = {"low", "front", "back", "third", "fourth"};
  for (int t = 0; t < 5; ++t) {
    glBindTextureUnit(GLuint(t), textures[t]);
    uniform1i(up, names[t], t);
  }
  uniform1i(up, "stride", stride);
  uniform1i(up, "clip_back", clip_back ? 1 : 0);
  uniform1i(up, "eye_inside", inside ? 1 : 0);
  glProgramUniform1f(up, glGetUniformLocation(up, "sigma_t"), float(current_.sigma_t_median));
  glProgramUniform1f(up, glGetUniformLocation(up, "depth_scale"),
                     float(4 * std::max(current_.sigma_median, 1e-6)));
  uniform1i(up, "phase_guide", per_ray ? 1 : 0);
  glProgramUniform1f(up, glGetUniformLocation(up, "g"), float(scene.medium.g));
  set_light_uniforms(up, scene.lights);
  set_camera_uniforms(up, scene);
  full.bind_and_clear(Vec3{});
  glDisable(GL_DEPTH_TEST);
  glUseProgram(up);
  glBindVertexArray(empty_vao_.get());
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glUseProgram(0);
  for (GLuint t = 0; t < 5; ++t) glBindTextureUnit(t, 0);
  gpu::check_gl("single upsample");
  glFinish();
  return full.read_color();
}

}  // namespace scatter
