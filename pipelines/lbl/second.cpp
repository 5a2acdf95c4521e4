#include "pipelines/lbl/second.hpp"

#include <algorithm>

#include "pipelines/common/cl_library.hpp"
#include "pipelines/common/cl_scene.hpp"
#include "pipelines/lbl/escape.hpp"

namespace scatter::lbl {

namespace {
// The mean of each 2 x 2 x 2 cell of a grid of `n` (3 channels; voxels past the high end count
// 0, as coarse_sigma's); `n` becomes the cells' grid.
std::vector<float> halve(const std::vector<float>& f, std::array<int, 3>& n) {
  const int cx = (n[0] + 1) / 2, cy = (n[1] + 1) / 2, cz = (n[2] + 1) / 2;
  std::vector<double> sum(3 * size_t(cx) * cy * cz, 0.0);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        size_t cell = (size_t(k / 2) * cy + j / 2) * cx + i / 2;
        size_t voxel = (size_t(k) * n[1] + j) * n[0] + i;
        for (int ch = 0; ch < 3; ++ch) sum[3 * cell + ch] += f[3 * voxel + ch] / 8.0;
      }
  n = {cx, cy, cz};
  return std::vector<float>(sum.begin(), sum.end());
}

cl::Program& second_program(gpu::ClContext& cl) {
  return cl.program(with_cl_library({"kernels/lbl/escape.cl", "kernels/lbl/second.cl"}));
}
}  // namespace

SecondScatter::SecondScatter(gpu::ClContext& cl, const Volume& v, const ClVolume& device, double g,
                             int stride, double far, int directions, int order_level)
    : cl_(cl),
      v_(device),
      g_(g),
      far_(stride > 1 ? far : 0),
      stride_(stride),
      directions_(directions),
      order_level_(order_level) {
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
  // next_order()'s grid: `order_level` halvings of the voxels, its cells' mean sigma_t', and the
  // cells within one cell of a cell holding a scattering voxel (the trilinear reads of a voxel's
  // centre stay within one cell of its own).
  std::vector<float> level_t = scaled;
  std::array<int, 3> ln = {v.nx, v.ny, v.nz};
  for (int l = 0; l < order_level_; ++l) level_t = halve(level_t, ln);
  level_n_ = ln;
  const size_t cells = size_t(ln[0]) * ln[1] * ln[2];
  std::vector<char> scatters(cells, 0), needed(cells, 0);
  for (int k = 0; k < v.nz; ++k)
    for (int j = 0; j < v.ny; ++j)
      for (int i = 0; i < v.nx; ++i) {
        size_t voxel = v.index(i, j, k);
        if (v.sigma_s[3 * voxel] > 0 || v.sigma_s[3 * voxel + 1] > 0 ||
            v.sigma_s[3 * voxel + 2] > 0)
          scatters[(size_t(k >> order_level_) * ln[1] + (j >> order_level_)) * ln[0] +
                   (i >> order_level_)] = 1;
      }
  for (int k = 0; k < ln[2]; ++k)
    for (int j = 0; j < ln[1]; ++j)
      for (int i = 0; i < ln[0]; ++i) {
        if (!scatters[(size_t(k) * ln[1] + j) * ln[0] + i]) continue;
        for (int c = std::max(0, k - 1); c <= std::min(ln[2] - 1, k + 1); ++c)
          for (int b = std::max(0, j - 1); b <= std::min(ln[1] - 1, j + 1); ++b)
            for (int a = std::max(0, i - 1); a <= std::min(ln[0] - 1, i + 1); ++a)
              needed[(size_t(c) * ln[1] + b) * ln[0] + a] = 1;
      }
  std::vector<cl_int> list;
  for (size_t c = 0; c < cells; ++c)
    if (needed[c]) list.push_back(static_cast<cl_int>(c));
  level_listed_ = list.size();
  sigma_s_ = device.sigma_s;
  level_t_ = upload(cl, level_t);
  level_list_ =
      cl::Buffer(cl.context(), CL_MEM_READ_ONLY, std::max<size_t>(1, list.size()) * sizeof(cl_int));
  if (!list.empty())
    cl.queue().enqueueWriteBuffer(level_list_, CL_TRUE, 0, list.size() * sizeof(cl_int),
                                  list.data());
  // Every level's source (level 1 is the far field's coarse_source_), and the cells' phi V.
  ln = {v.nx, v.ny, v.nz};
  for (int l = 1; l <= order_level_; ++l) {
    ln = {(ln[0] + 1) / 2, (ln[1] + 1) / 2, (ln[2] + 1) / 2};
    level_sources_.emplace_back(cl.context(), CL_MEM_READ_WRITE,
                                3 * size_t(ln[0]) * ln[1] * ln[2] * sizeof(float));
  }
  level_phi_ = cl::Buffer(cl.context(), CL_MEM_READ_WRITE, 3 * cells * sizeof(float));
  cl.queue().enqueueFillBuffer(level_phi_, 0.f, 0, 3 * cells * sizeof(float));
}

void SecondScatter::next_order(const cl::Buffer& source, cl::Buffer& out, cl::Buffer& sum) {
  cl::Program& program = second_program(cl_);
  auto& queue = cl_.queue();
  std::array<int, 3> ln = {v_.nx, v_.ny, v_.nz};
  const cl::Buffer* from = &source;
  for (cl::Buffer& to : level_sources_) {
    cl::Kernel average(program, "second_coarse");
    gpu::set_args(average, ln[0], ln[1], ln[2], *from, to);
    ln = {(ln[0] + 1) / 2, (ln[1] + 1) / 2, (ln[2] + 1) / 2};
    queue.enqueueNDRangeKernel(average, cl::NullRange, cl::NDRange(ln[0], ln[1], ln[2]));
    from = &to;
  }
  const int factor = 1 << order_level_;
  if (level_listed_ > 0) {
    cl::Kernel gather(program, "second_coarse_gather");
    gpu::set_args(gather, v_.origin, float(v_.voxel * factor), ln[0], ln[1], ln[2], level_t_, *from,
                  dirs_, directions_, level_list_, cl_int(level_listed_), level_phi_);
    queue.enqueueNDRangeKernel(gather, cl::NullRange, cl::NDRange(level_listed_));
  }
  cl::Kernel back(program, "second_from_coarse");
  gpu::set_args(back, v_.nx, v_.ny, v_.nz, factor, ln[0], ln[1], ln[2], level_phi_, sigma_s_,
                float(g_), out, sum);
  queue.enqueueNDRangeKernel(back, cl::NullRange, cl::NDRange(v_.nx, v_.ny, v_.nz));
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
