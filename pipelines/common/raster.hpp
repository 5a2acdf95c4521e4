// Rasterisation pieces shared by the pipelines that draw the mesh: camera matrices, the mesh in GL
// buffers, and an offscreen float colour + depth target whose depth later passes can read.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gpu/gl_objects.hpp"
#include "pipelines/image.hpp"
#include "scene/scene.hpp"
#include "scene/solid.hpp"

namespace scatter {

struct CameraMatrices {
  Mat4 view;
  Mat4 projection;
  double z_near = 0.01, z_far = 100;
};

// Near and far planes hug the mesh's bounding sphere so depth precision goes where the object is.
CameraMatrices camera_matrices(const Scene& scene);

class MeshBuffers {
 public:
  // Uploads positions and normals (attributes 0 and 1) and the indices.
  explicit MeshBuffers(const Mesh& mesh);
  void draw() const;

 private:
  gpu::GlObject vao_, vertices_, indices_;
  GLsizei count_ = 0;
};

// What identifies the scene's mesh: its mesh_id, else its digest (which costs a pass over it).
std::string mesh_key(const Scene& scene);

// The scene's mesh in GL buffers, kept across frames while the mesh stays the same (a camera or
// light move uploads nothing): the pipelines that draw the mesh every frame keep one.
class KeptMesh {
 public:
  const MeshBuffers& get(const Scene& scene);
  // Whether the camera is inside the object (the drawn mesh's parity just ahead of the eye, its
  // solid kept while the scene holds the same mesh): then every view ray starts in the medium,
  // and the first surface depth peeling finds is where it leaves, so the medium along the ray is
  // [eye, 1st], [2nd, 3rd] rather than [1st, 2nd], [3rd, 4th]. A camera outside the mesh's box
  // costs a box test.
  bool eye_inside(const Scene& scene);

 private:
  std::string key_;
  std::unique_ptr<MeshBuffers> mesh_;
  std::shared_ptr<const Mesh> solid_mesh_;  // what solid_ refers to (declared first: dies last)
  std::unique_ptr<Solid> solid_;
};

class RenderTarget {
 public:
  // RGBA32F colour and 32-bit float depth textures of the given size.
  RenderTarget(int width, int height);
  void bind_and_clear(const Vec3& background);
  // Colour as linear RGB, row 0 at the top.
  Image read_color() const;
  // Window-space depth in [0, 1], row 0 at the top.
  std::vector<float> read_depth() const;
  GLuint depth_texture() const { return depth_.get(); }
  GLuint color_texture() const { return color_.get(); }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  gpu::GlObject fbo_, color_, depth_;
};

// Uniform helpers (glProgramUniform*, by name).
std::string indexed(const char* name, size_t i);  // "name[i]", for uniform arrays
void uniform3(GLuint program, const std::string& name, const Vec3& v);
void uniform1i(GLuint program, const std::string& name, int v);
void uniform_matrix(GLuint program, const std::string& name, const Mat4& m);

// light_count and, per light, light_type (0 point, 1 directional, 2 spot), light_position,
// light_direction, light_power (colour x intensity), light_cone (cos outer, cos inner).
void set_light_uniforms(GLuint program, const std::vector<Light>& lights);
// eye, forward, right, up (scaled as CameraFrame) and size, for shaders that rebuild the pixel's
// ray from gl_FragCoord.
void set_camera_uniforms(GLuint program, const Scene& scene);

// The program draw_distance() draws with: shaders/common/distance.*.
gpu::GlObject build_distance_program();

// Draws the mesh into `target` with build_distance_program()'s program, writing the distance from
// `origin` (along rays, or along `direction` when `along_direction`); with `first_layer` (a
// previous layer's texture) only surfaces behind it are kept: depth peeling. Red holds the
// distance at the texel's centre, green and blue its change per texel along x and y on the
// surface drawn there (shaders/common/distance.frag); texels no surface covers hold (`empty`, 0,
// 0).
void draw_distance(GLuint program, const MeshBuffers& mesh, RenderTarget& target, const Mat4& view,
                   const Mat4& projection, const Vec3& origin, const Vec3& direction,
                   bool along_direction, GLuint first_layer, float empty = 0.f);

// Where a light's shadow map looks from and how it projects; `origin` and `direction` define the
// distance the map stores (along rays from a point, or along the direction for directional light).
struct LightView {
  Mat4 view, projection;
  Vec3 origin, direction;
  bool along_direction = false;
};

// Throws ValidationError (scene.lights) for a point or spot light inside the object's bounding
// sphere, naming `pipeline`.
LightView light_view(const Light& l, const Scene& scene, const std::string& pipeline);

}  // namespace scatter
