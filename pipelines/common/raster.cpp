#include "pipelines/common/raster.hpp"

#include <cmath>
#include <numbers>

#include "core/errors.hpp"

namespace scatter {

CameraMatrices camera_matrices(const Scene& scene) {
  const Camera& cam = scene.camera;
  Aabb b = scene.mesh->bounds();
  double radius = length(b.size()) / 2;
  double dist = length(b.center() - cam.position);
  CameraMatrices m;
  m.z_far = dist + radius * 1.05 + 1e-3;
  m.z_near = std::max(m.z_far * 1e-4, (dist - radius * 1.05) * 0.95);
  m.view = look_at(cam.position, cam.target, cam.up);
  m.projection = perspective(cam.fov_deg * std::numbers::pi / 180,
                             double(scene.width) / scene.height, m.z_near, m.z_far);
  return m;
}

std::string mesh_key(const Scene& scene) {
  return scene.mesh_id.empty() ? mesh_digest(*scene.mesh) : scene.mesh_id;
}

const MeshBuffers& KeptMesh::get(const Scene& scene) {
  std::string key = mesh_key(scene);
  if (!mesh_ || key != key_) {
    mesh_.reset();  // the old buffers go first
    mesh_ = std::make_unique<MeshBuffers>(*scene.mesh);
    key_ = std::move(key);
  }
  return *mesh_;
}

bool KeptMesh::eye_inside(const Scene& scene) {
  // The mesh that is depth-peeled decides (a procedural shape's tessellation, not the exact
  // shape: an eye between the two would get the wrong intervals), at a point a hair ahead of the
  // eye, where its rays are: an eye on a face then counts as inside when it looks in.
  const Mesh& mesh = *scene.mesh;
  const Aabb b = mesh.bounds();
  const double hair = 1e-6 * std::max(length(b.size()), 1e-30);
  const Vec3 e = scene.camera.position + camera_frame(scene.camera, 1, 1).forward * hair;
  if (e.x < b.lo.x || e.y < b.lo.y || e.z < b.lo.z || e.x > b.hi.x || e.y > b.hi.y || e.z > b.hi.z)
    return false;
  if (!solid_ || solid_mesh_ != scene.mesh) {
    solid_.reset();  // before the mesh it refers to
    solid_mesh_ = scene.mesh;
    solid_ = make_mesh_solid(*solid_mesh_);
  }
  std::vector<char> inside;
  solid_->classify_column(e.x, e.y, {e.z}, inside);
  return inside[0] != 0;
}

MeshBuffers::MeshBuffers(const Mesh& mesh) {
  std::vector<float> interleaved;
  interleaved.reserve(mesh.positions.size() * 6);
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    for (const Vec3* v : {&mesh.positions[i], &mesh.normals[i]})
      for (int c = 0; c < 3; ++c) interleaved.push_back(static_cast<float>((*v)[c]));
  vertices_ = gpu::GlObject::create(gpu::GlKind::Buffer);
  indices_ = gpu::GlObject::create(gpu::GlKind::Buffer);
  vao_ = gpu::GlObject::create(gpu::GlKind::VertexArray);
  glNamedBufferData(vertices_.get(), static_cast<GLsizeiptr>(interleaved.size() * sizeof(float)),
                    interleaved.data(), GL_STATIC_DRAW);
  glNamedBufferData(indices_.get(), static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(uint32_t)),
                    mesh.indices.data(), GL_STATIC_DRAW);
  glVertexArrayVertexBuffer(vao_.get(), 0, vertices_.get(), 0, 6 * sizeof(float));
  glVertexArrayElementBuffer(vao_.get(), indices_.get());
  for (GLuint attr : {0u, 1u}) {
    glEnableVertexArrayAttrib(vao_.get(), attr);
    glVertexArrayAttribFormat(vao_.get(), attr, 3, GL_FLOAT, GL_FALSE, attr * 3 * sizeof(float));
    glVertexArrayAttribBinding(vao_.get(), attr, 0);
  }
  count_ = static_cast<GLsizei>(mesh.indices.size());
  gpu::check_gl("mesh upload");
}

void MeshBuffers::draw() const {
  glBindVertexArray(vao_.get());
  glDrawElements(GL_TRIANGLES, count_, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
}

RenderTarget::RenderTarget(int width, int height) : width_(width), height_(height) {
  auto texture = [&](GLenum format) {
    gpu::GlObject t = gpu::GlObject::create(gpu::GlKind::Texture);
    glBindTexture(GL_TEXTURE_2D, t.get());
    glTexStorage2D(GL_TEXTURE_2D, 1, format, width, height);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTexture(GL_TEXTURE_2D, 0);
    return t;
  };
  color_ = texture(GL_RGBA32F);
  depth_ = texture(GL_DEPTH_COMPONENT32F);
  fbo_ = gpu::GlObject::create(gpu::GlKind::Framebuffer);
  glNamedFramebufferTexture(fbo_.get(), GL_COLOR_ATTACHMENT0, color_.get(), 0);
  glNamedFramebufferTexture(fbo_.get(), GL_DEPTH_ATTACHMENT, depth_.get(), 0);
  if (glCheckNamedFramebufferStatus(fbo_.get(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw gpu::GpuError("the float colour + depth framebuffer is incomplete on this driver");
  gpu::check_gl("render target");
}

void RenderTarget::bind_and_clear(const Vec3& background) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
  glViewport(0, 0, width_, height_);
  glClearColor(float(background.x), float(background.y), float(background.z), 1.f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

Image RenderTarget::read_color() const {
  std::vector<float> rgba(size_t(width_) * height_ * 4);
  glGetTextureImage(color_.get(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(rgba.size() * 4),
                    rgba.data());
  gpu::check_gl("colour read-back");
  Image image(width_, height_);
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x)
      for (int c = 0; c < 3; ++c)  // GL's row 0 is the bottom
        image.rgb[(size_t(y) * width_ + x) * 3 + c] =
            rgba[(size_t(height_ - 1 - y) * width_ + x) * 4 + c];
  return image;
}

std::vector<float> RenderTarget::read_depth() const {
  std::vector<float> gl_rows(size_t(width_) * height_), rows(gl_rows.size());
  glGetTextureImage(depth_.get(), 0, GL_DEPTH_COMPONENT, GL_FLOAT,
                    static_cast<GLsizei>(gl_rows.size() * 4), gl_rows.data());
  gpu::check_gl("depth read-back");
  for (int y = 0; y < height_; ++y)
    std::copy_n(&gl_rows[size_t(height_ - 1 - y) * width_], width_, &rows[size_t(y) * width_]);
  return rows;
}

// "name[i]", for uniform arrays.
std::string indexed(const char* name, size_t i) {
  std::string s = name;
  s.append("[").append(std::to_string(i)).append("]");
  return s;
}

void uniform3(GLuint p, const std::string& name, const Vec3& v) {
  glProgramUniform3f(p, glGetUniformLocation(p, name.c_str()), float(v.x), float(v.y), float(v.z));
}
void uniform1i(GLuint p, const std::string& name, int v) {
  glProgramUniform1i(p, glGetUniformLocation(p, name.c_str()), v);
}
void uniform_matrix(GLuint p, const std::string& name, const Mat4& m) {
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, name.c_str()), 1, GL_FALSE, m.m.data());
}

gpu::GlObject build_distance_program() {
  return gpu::build_program("shaders/common/distance.vert", "shaders/common/distance.frag");
}

void draw_distance(GLuint program, const MeshBuffers& mesh, RenderTarget& target, const Mat4& view,
                   const Mat4& projection, const Vec3& origin, const Vec3& direction,
                   bool along_direction, GLuint first_layer, float empty) {
  uniform_matrix(program, "view", view);
  uniform_matrix(program, "projection", projection);
  uniform3(program, "origin", origin);
  uniform3(program, "direction", direction);
  uniform1i(program, "along_direction", along_direction);
  uniform1i(program, "peel", first_layer != 0);
  uniform1i(program, "first_layer", 0);
  glBindTextureUnit(0, first_layer);
  target.bind_and_clear(Vec3{empty, 0, 0});  // no slopes where no surface is
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glUseProgram(program);
  mesh.draw();
  glUseProgram(0);
  glBindTextureUnit(0, 0);
}

void set_light_uniforms(GLuint p, const std::vector<Light>& lights) {
  const double to_rad = std::numbers::pi / 180;
  for (size_t i = 0; i < lights.size(); ++i) {
    const Light& l = lights[i];
    uniform1i(p, indexed("light_type", i),
              l.type == Light::Type::Point ? 0 : (l.type == Light::Type::Directional ? 1 : 2));
    uniform3(p, indexed("light_position", i), l.position);
    uniform3(p, indexed("light_direction", i), l.direction);
    uniform3(p, indexed("light_power", i), l.color * l.intensity);
    glProgramUniform2f(p, glGetUniformLocation(p, indexed("light_cone", i).c_str()),
                       float(std::cos(l.outer_deg * to_rad)),
                       float(std::cos(l.inner_deg * to_rad)));
  }
  uniform1i(p, "light_count", static_cast<int>(lights.size()));
}

void set_camera_uniforms(GLuint p, const Scene& scene) {
  CameraFrame frame = camera_frame(scene.camera, scene.width, scene.height);
  uniform3(p, "eye", scene.camera.position);
  uniform3(p, "forward", frame.forward);
  uniform3(p, "right", frame.right);
  uniform3(p, "up", frame.up);
  glProgramUniform2f(p, glGetUniformLocation(p, "size"), float(scene.width), float(scene.height));
}

LightView light_view(const Light& l, const Scene& scene, const std::string& pipeline) {
  Aabb b = scene.mesh->bounds();
  Vec3 c = b.center();
  double radius = length(b.size()) / 2 * 1.02;
  LightView v;
  if (l.type == Light::Type::Directional) {
    v.direction = l.direction;
    v.origin = c - l.direction * (2 * radius);
    v.along_direction = true;
    Vec3 up = std::abs(l.direction.y) < 0.9 ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
    v.view = look_at(v.origin, c, up);
    v.projection = orthographic(radius, radius * 0.5, radius * 3.5);
    return v;
  }
  double dist = length(c - l.position);
  if (dist <= radius * 1.01)
    throw ValidationError("scene.lights", "the " + pipeline +
                                              " pipeline's shadow maps need every point or "
                                              "spot light outside the object's bounding sphere");
  v.origin = l.position;
  v.direction = normalize(c - l.position);
  Vec3 up = std::abs(v.direction.y) < 0.9 ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  v.view = look_at(l.position, c, up);
  double half_angle = std::asin(radius / dist);
  v.projection =
      perspective(2 * half_angle * 1.02, 1.0, std::max(dist - radius, dist * 1e-3), dist + radius);
  return v;
}

}  // namespace scatter
