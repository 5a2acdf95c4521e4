#include "pipelines/lbl/second.hpp"

#include <algorithm>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/lbl/escape.hpp"

namespace scatter::lbl {

namespace {
cl::Program& second_program(gpu::ClContext& cl) {
  return cl.program(with_cl_library({"kernels/lbl/escape.cl", "kernels/lbl/second.cl"}));
}
}  // namespace

SecondScatter::SecondScatter(gpu::ClContext& cl, const Volume& v, const ClVolume& device, double g,
                             int stride, double far, int directions)
    : cl_(cl),
      v_(device),
      g_(g),
      far_(stride > 1 ? far : 0),
      stride_(stride),
      directions_(directions) {
  std::vector<float> scaled(v.sigma_t.size());
  for (size_t i = 0; i < scaled.size(); ++i)
    scaled[i] = static_cast<float>(v.sigma_t[i] - g * v.sigma_s[i]);
  sigma_t_ = upload(cl, scaled);
  coarse_t_ = upload(cl, coarse_sigma(v, scaled));
  count_ = v.count();
  coarse_count_ = size_t((v.nx + 1) / 2) * ((v.ny + 1) / 2) * ((v.nz + 1) / 2);
  coarse_source_ = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 3 * coarse_count_ * sizeof(float));
  dirs_ = upload(cl, fibonacci_directions(directions));
  EscapeSampling e;
  if (stride > 1) {
    e = escape_sampling(v, scaled, stride);
  } else {  // every scattering voxel computed itself
    e.n = {1, 1, 1};
    e.mode.assign(v.count(), 0);
    for (size_t i = 0; i < v.count(); ++i)
      if (v.sigma_s[3 * i] > 0 || v.sigma_s[3 * i + 1] > 0 || v.sigma_s[3 * i + 2] > 0)
        e.mode[i] = 2;
  }
  n_ = e.n;
  samples_count_ = e.samples.size();
  gathers_ = samples_count_ + size_t(std::count(e.mode.begin(), e.mode.end(), 2));
  list_ = cl::Buffer(cl.context(), CL_MEM_READ_ONLY,
                     std::max<size_t>(1, samples_count_) * sizeof(cl_int));
  if (samples_count_ > 0)
    cl.queue().enqueueWriteBuffer(list_, CL_TRUE, 0, samples_count_ * sizeof(cl_int),
                                  e.samples.data());
  mode_ = cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, e.mode.size(),
                     e.mode.data());
  const size_t sample_floats = std::max<size_t>(1, 3 * size_t(n_[0]) * n_[1] * n_[2]);
  samples_ = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, sample_floats * sizeof(float));
  msamples_ = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, sample_floats * sizeof(float));
}

void SecondScatter::run(const cl::Buffer& source, cl::Buffer& out, cl::Buffer& direction,
                        const std::function<void(double)>& progress) {
  cl::Program& program = second_program(cl_);
  auto& queue = cl_.queue();
  // Launches: the samples' in chunks, then the interpolation's in slabs of whole z layers, each
  // about kSecondChunk voxels.
  const size_t layer = size_t(v_.nx) * v_.ny;
  const int slab = static_cast<int>(std::max<size_t>(1, kSecondChunk / std::max<size_t>(1, layer)));
  const size_t launches =
      (samples_count_ + kSecondChunk - 1) / kSecondChunk + size_t((v_.nz + slab - 1) / slab);
  size_t done = 0;
  auto launched = [&] {
    if (!progress) return;
    queue.finish();
    progress(double(++done) / double(launches));
  };
  const int cx = (v_.nx + 1) / 2, cy = (v_.ny + 1) / 2, cz = (v_.nz + 1) / 2;
  if (far_ > 0) {
    cl::Kernel k(program, "second_coarse");
    gpu::set_args(k, v_.nx, v_.ny, v_.nz, source, coarse_source_);
    queue.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(cx, cy, cz));
  }
  if (samples_count_ > 0) {
    cl::Kernel k(program, "second_samples");
    gpu::set_args(k, v_.origin, v_.voxel, v_.nx, v_.ny, v_.nz, sigma_t_, source, coarse_t_,
                  coarse_source_, float(far_), dirs_, directions_, stride_, n_[0], n_[1], list_,
                  cl_int(samples_count_), samples_, msamples_);
    for (size_t first = 0; first < samples_count_; first += kSecondChunk) {
      queue.enqueueNDRangeKernel(k, cl::NDRange(first),
                                 cl::NDRange(std::min(kSecondChunk, samples_count_ - first)));
      launched();
    }
  }
  cl::Kernel k(program, "second_interpolate");
  gpu::set_args(k, v_.origin, v_.voxel, v_.nx, v_.ny, v_.nz, sigma_t_, source, coarse_t_,
                coarse_source_, float(far_), mode_, dirs_, directions_, stride_, n_[0], n_[1],
                samples_, msamples_, v_.sigma_s, float(g_), out, direction);
  for (int z = 0; z < v_.nz; z += slab) {
    queue.enqueueNDRangeKernel(k, cl::NDRange(0, 0, z),
                               cl::NDRange(v_.nx, v_.ny, std::min(slab, v_.nz - z)));
    launched();
  }
}

}  // namespace scatter::lbl
