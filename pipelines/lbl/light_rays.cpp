#include "pipelines/lbl/light_rays.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"

namespace scatter::lbl {
namespace {

constexpr double kPi = std::numbers::pi;

const std::vector<std::string> kProgram =
    with_cl_library({"kernels/lbl/common.cl", "kernels/lbl/march.cl"});

void basis(const Vec3& w, Vec3& u, Vec3& v) {
  Vec3 h = std::abs(w.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  u = normalize(cross(h, w));
  v = cross(w, u);
}

// Shirley and Chiu's concentric map of [-1, 1]^2 onto the unit disk (area preserving up to a
// constant): radius and angle.
void concentric(double a, double b, double& r, double& phi) {
  if (a == 0 && b == 0) {
    r = phi = 0;
  } else if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = kPi / 4 * (b / a);
  } else {
    r = b;
    phi = kPi / 2 - kPi / 4 * (a / b);
  }
  if (r < 0) {  // the map's radius is signed: the point is (r cos phi, r sin phi)
    r = -r;
    phi += kPi;
  }
}

void push(RaySet& set, const Vec3& o, const Vec3& d, const Vec3& power) {
  for (const Vec3* p : {&o, &d, &power})
    for (int c = 0; c < 3; ++c) set.rays.push_back(static_cast<float>((*p)[c]));
  for (int c = 0; c < 3; ++c) set.rays.push_back(0.f);
}

}  // namespace

RaySet light_rays(const std::vector<Light>& lights, const Volume& v, double per_voxel,
                  int max_side) {
  const Vec3 size = Vec3{double(v.nx), double(v.ny), double(v.nz)} * v.voxel;
  const Vec3 centre = v.origin + size * 0.5;
  const double radius = 0.5 * length(size);
  const int side =
      std::clamp(static_cast<int>(std::ceil(per_voxel * 2 * radius / v.voxel)), 2, max_side);
  RaySet set;
  for (const Light& l : lights) {
    Vec3 power = l.color * l.intensity;
    if (l.type == Light::Type::Directional) {
      Vec3 d = normalize(l.direction), u, w;
      basis(d, u, w);
      const double cell = 2 * radius / side;
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          double a = -radius + (i + 0.5) * cell, b = -radius + (j + 0.5) * cell;
          if (a * a + b * b > radius * radius) continue;  // misses the bounding sphere
          Vec3 o = centre - d * (radius + v.voxel) + u * a + w * b;
          push(set, o, d, power * (cell * cell));
        }
      continue;
    }
    Vec3 to_centre = centre - l.position;
    double dist = length(to_centre);
    Vec3 axis = dist > 0 ? to_centre / dist : Vec3{0, 0, 1}, u, w;
    basis(axis, u, w);
    double cos_max = dist > radius ? std::sqrt(1 - (radius / dist) * (radius / dist)) : -1.0;
    double solid_angle = 2 * kPi * (1 - cos_max) / (double(side) * side);
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        double r, phi;
        concentric(2 * (i + 0.5) / side - 1, 2 * (j + 0.5) / side - 1, r, phi);
        double ct = 1 - r * r * (1 - cos_max), st = std::sqrt(std::max(0.0, 1 - ct * ct));
        Vec3 d = normalize(axis * ct + u * (st * std::cos(phi)) + w * (st * std::sin(phi)));
        double cone = spot_cone(l, d);
        if (cone <= 0) continue;
        push(set, l.position, d, power * (solid_angle * cone));
      }
  }
  return set;
}

void march(gpu::ClContext& cl, const ClVolume& v, const cl::Buffer& rays, int count, bool bend,
           double step, double cutoff, double g, cl::Buffer& deposit, cl::Buffer& source,
           cl::Buffer* flow) {
  if (count == 0) return;
  cl::Kernel k(cl.program(kProgram), "march_rays");
  gpu::set_args(k, v.origin, v.voxel, v.nx, v.ny, v.nz, v.sigma_s, v.sigma_t, v.n, v.grad, rays,
                count, bend ? 1 : 0, float(step), float(cutoff), float(g), deposit, source,
                flow ? *flow : deposit, flow ? 1 : 0);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(size_t(count)));
}

std::vector<float> eikonal_trace(gpu::ClContext& cl, const ClVolume& v, const RaySet& rays,
                                 double step, int steps) {
  std::vector<float> out(size_t(3) * steps * rays.count());
  cl::Buffer ray_buf = upload(cl, rays.rays);
  cl::Buffer out_buf(cl.context(), CL_MEM_WRITE_ONLY,
                     std::max<size_t>(out.size(), 1) * sizeof(float));
  cl::Kernel k(cl.program(kProgram), "eikonal_trace");
  gpu::set_args(k, v.origin, v.voxel, v.nx, v.ny, v.nz, v.n, v.grad, ray_buf, rays.count(),
                float(step), steps, out_buf);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(size_t(std::max(rays.count(), 1))));
  cl.queue().enqueueReadBuffer(out_buf, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  return out;
}

}  // namespace scatter::lbl
