// The `single` pipeline's exact-transmittance shading (setting exact_tr, kernels/single/shade.cl):
// per frame each sample's factor and, with tr_gradient, its Gaussian's move and per-axis sigma;
// each light's transmittance (and gradient) is kept while the light stays put.
#include <map>

#include "pipelines/common/boundary_planes.hpp"
#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/single/bake_support.hpp"
#include "pipelines/single/single_pipeline.hpp"

namespace scatter {

void SinglePipeline::shade_exact(const Scene& scene, const DrawnSamples& drawn, bool gradient,
                                 bool hessian, double max_gs, bool mesh_bound) {
  const SingleBake& b = *current_.bake;
  const VoxelGrid& g = *current_.grid;
  gpu::ClContext& cl = gpu_.cl();
  if (!current_.cl_uploaded) {
    // The voxels' mean extinction and the baked anchors (mesh_bound 0: no planes, a null buffer).
    std::vector<float> st(g.sigma_s.size());
    for (size_t i = 0; i < st.size(); ++i) st[i] = g.sigma_s[i] + g.sigma_a[i];
    cl_sigma_t_ = scatter::upload(cl, st);
    cl_at_ = scatter::upload(cl, b.depth_at);
    cl_position_ = scatter::upload(cl, b.position);
    cl_sigma_ = scatter::upload(cl, b.sigma);
    cl_weight_ = scatter::upload(cl, b.weight);
    // Without a coarse set (under 1024 samples) the same buffer: drawn.coarse is never set then.
    cl_coarse_weight_ = b.coarse_weight.empty() ? cl_weight_ : scatter::upload(cl, b.coarse_weight);
    cl_sigma_s_ = scatter::upload(cl, b.sigma_s);
    // The pieces' planes in their anchors' frame (a split shell sample's anchor is moved into the
    // medium; its differences are tested on its side of its plane moved with it).
    cl_plane_ = scatter::upload(cl, b.plane.empty()
                                        ? std::vector<float>(size_t(std::max(b.count, 1)) * 4, 0.f)
                                        : single_detail::depth_frame_planes(b));
    cl_out_ = cl::Buffer(cl.context(), CL_MEM_WRITE_ONLY,
                         size_t(std::max(b.count, 1)) * 4 * sizeof(float));
    cl_shift_ = cl::Buffer(cl.context(), CL_MEM_WRITE_ONLY,
                           size_t(std::max(b.count, 1)) * 4 * sizeof(float));
    cl_axes_ = cl::Buffer(cl.context(), CL_MEM_WRITE_ONLY,
                          size_t(std::max(b.count, 1)) * 4 * sizeof(float));
    // Three float4 a sample: the linear depth cut, the quadratic model's slope and depth, its
    // curvature (kernels/single/shade.cl).
    cl_cut_ = cl::Buffer(cl.context(), CL_MEM_WRITE_ONLY,
                         size_t(std::max(b.count, 1)) * 12 * sizeof(float));
    current_.cl_uploaded = true;
  }
  if (mesh_bound && !current_.cl_bounded) {
    // The medium the splat sees: bounded by the mesh, sigma_s per unit medium (the bake's), so
    // that the optical depths are of the same medium (pipelines/common/boundary_planes.hpp).
    const BoundedExtinction bounded = bounded_extinction(g);
    cl_bounded_sigma_t_ = scatter::upload(cl, bounded.sigma_t);
    cl_bound_ = scatter::upload(cl, bounded.plane);
    // Anchors in a boundary voxel's empty part measure from the mesh's side of its plane.
    std::vector<float> at(b.depth_at.size());
    for (size_t i = 0; 3 * i < at.size(); ++i) {
      const Vec3 p = inside_bound(
          g, bounded, Vec3{b.depth_at[3 * i], b.depth_at[3 * i + 1], b.depth_at[3 * i + 2]});
      at[3 * i] = float(p.x);
      at[3 * i + 1] = float(p.y);
      at[3 * i + 2] = float(p.z);
    }
    cl_bounded_at_ = scatter::upload(cl, at);
    current_.cl_bounded = true;
  }
  const cl::Buffer& sigma_t = mesh_bound ? cl_bounded_sigma_t_ : cl_sigma_t_;
  const cl::Buffer bound = mesh_bound ? cl_bound_ : cl::Buffer();  // null: the kernels read none
  const cl::Buffer& anchors = mesh_bound ? cl_bounded_at_ : cl_at_;
  const std::vector<std::string> program = with_cl_library({"kernels/single/shade.cl"});
  cl::Buffer lights = scatter::upload(cl, pack_lights(scene.lights));
  cl_float3 origin{{float(g.origin.x), float(g.origin.y), float(g.origin.z)}};
  const size_t block = size_t(std::max(b.count, 1)) * 3 * sizeof(float);
  // Transmittance to each light, kept while the light stays where it is (its position, or its
  // direction for a directional light, is the key).
  std::map<std::string, std::pair<cl::Buffer, cl::Buffer>> still_used;
  cl::Buffer all(cl.context(), CL_MEM_READ_WRITE, block * std::max<size_t>(scene.lights.size(), 1));
  cl::Buffer all_grad(cl.context(), CL_MEM_READ_WRITE,
                      2 * block * std::max<size_t>(scene.lights.size(), 1));
  cl::Kernel per_light(cl.program(program), "light_transmittance");
  for (size_t l = 0; l < scene.lights.size(); ++l) {
    const Light& light = scene.lights[l];
    const Vec3& where = light.type == Light::Type::Directional ? light.direction : light.position;
    std::string key = std::to_string(int(light.type)) + ":" + exact_number(where.x) + "," +
                      exact_number(where.y) + "," + exact_number(where.z) +
                      (mesh_bound ? ":m" : "") + (gradient ? ":g" : "");
    auto found = current_.light_tr.find(key);
    // A frame without the gradient can use a kept pass with it (the transmittance is the same):
    // the live view's moving frames and its still frame share the light's pass.
    if (found == current_.light_tr.end() && !gradient) {
      found = current_.light_tr.find(key + ":g");
      if (found != current_.light_tr.end()) key += ":g";
    }
    std::pair<cl::Buffer, cl::Buffer> tr;
    if (found != current_.light_tr.end()) {
      tr = found->second;
    } else {
      tr = {cl::Buffer(cl.context(), CL_MEM_READ_WRITE, block),
            cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 2 * block)};
      gpu::set_args(per_light, origin, float(g.voxel), g.nx, g.ny, g.nz, sigma_t, bound, anchors,
                    cl_sigma_, cl_plane_, b.count, lights, static_cast<int>(l), gradient ? 1 : 0,
                    tr.first, tr.second);
      cl.queue().enqueueNDRangeKernel(per_light, cl::NullRange,
                                      cl::NDRange(size_t(std::max(b.count, 1))));
      ++current_.light_passes;
    }
    cl.queue().enqueueCopyBuffer(tr.first, all, 0, l * block, block);
    if (gradient) cl.queue().enqueueCopyBuffer(tr.second, all_grad, 0, 2 * l * block, 2 * block);
    still_used[key] = tr;
  }
  current_.light_tr = std::move(still_used);
  // Each light's share per sample, without its phase (the splat takes it per view ray).
  const size_t per_light_floats =
      size_t(std::max(b.count, 1)) * 4 * std::max<size_t>(scene.lights.size(), 1);
  if (per_light_floats != light_factor_floats_) {
    cl_light_factor_ =
        cl::Buffer(cl.context(), CL_MEM_WRITE_ONLY, per_light_floats * sizeof(float));
    gpu_.gl().make_current();
    light_factors_ = gpu::GlObject::create(gpu::GlKind::Buffer);
    glNamedBufferStorage(light_factors_.get(),
                         static_cast<GLsizeiptr>(per_light_floats * sizeof(float)), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
    light_factor_floats_ = per_light_floats;
  }
  cl::Kernel k(cl.program(program), "shade_exact");
  const Vec3& e = scene.camera.position;
  cl_float3 eye{{float(e.x), float(e.y), float(e.z)}};
  gpu::set_args(k, origin, float(g.voxel), g.nx, g.ny, g.nz, sigma_t, bound, anchors, cl_position_,
                cl_sigma_, drawn.coarse ? cl_coarse_weight_ : cl_weight_, cl_sigma_s_, cl_plane_,
                b.count, lights, static_cast<int>(scene.lights.size()), all, all_grad,
                gradient ? 1 : 0, hessian ? 1 : 0, float(max_gs), float(scene.medium.g), eye,
                float(drawn.sigma_scale), cl_out_, cl_shift_, cl_axes_, cl_cut_, cl_light_factor_);
  for (const auto& [first, count] : drawn.ranges)
    if (count > 0)
      cl.queue().enqueueNDRangeKernel(k, cl::NDRange(size_t(first)), cl::NDRange(size_t(count)));
  std::vector<float> out(size_t(b.count) * 4), shift(size_t(b.count) * 4),
      axes(size_t(b.count) * 4), cut(size_t(b.count) * 12);
  cl.queue().enqueueReadBuffer(cl_out_, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  cl.queue().enqueueReadBuffer(cl_shift_, CL_TRUE, 0, shift.size() * sizeof(float), shift.data());
  cl.queue().enqueueReadBuffer(cl_axes_, CL_TRUE, 0, axes.size() * sizeof(float), axes.data());
  cl.queue().enqueueReadBuffer(cl_cut_, CL_TRUE, 0, cut.size() * sizeof(float), cut.data());
  // The per-light shares only where the splat reads them (no readback on the hot path otherwise).
  const bool per_ray = phase_per_ray(scene, current_.sigma_median);
  std::vector<float> shares(per_ray ? per_light_floats : 0, 0.f);
  if (per_ray)
    cl.queue().enqueueReadBuffer(cl_light_factor_, CL_TRUE, 0,
                                 size_t(b.count) * 4 * scene.lights.size() * sizeof(float),
                                 shares.data());
  gpu_.gl().make_current();
  glNamedBufferSubData(colors_.get(), 0, static_cast<GLsizeiptr>(out.size() * sizeof(float)),
                       out.data());
  glNamedBufferSubData(shifts_.get(), 0, static_cast<GLsizeiptr>(shift.size() * sizeof(float)),
                       shift.data());
  glNamedBufferSubData(axes_.get(), 0, static_cast<GLsizeiptr>(axes.size() * sizeof(float)),
                       axes.data());
  glNamedBufferSubData(cuts_.get(), 0, static_cast<GLsizeiptr>(cut.size() * sizeof(float)),
                       cut.data());
  if (per_ray)
    glNamedBufferSubData(light_factors_.get(), 0,
                         static_cast<GLsizeiptr>(shares.size() * sizeof(float)), shares.data());
}

}  // namespace scatter
