#include "pipelines/reference/slab.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "pipelines/common/cl_library.hpp"

namespace scatter {
namespace {

constexpr int kTallies = 14;

void check(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw ValidationError(field, problem);
}

}  // namespace

void to_json(nlohmann::json& j, const SlabResult& r) {
  j = {{"R", r.R},
       {"T", r.T},
       {"R_diffuse", r.R_diffuse},
       {"R_specular", r.R_specular},
       {"T_diffuse", r.T_diffuse},
       {"T_direct", r.T_direct},
       {"R_single", r.R_single},
       {"T_single", r.T_single},
       {"R_stderr", r.R_stderr},
       {"T_stderr", r.T_stderr},
       {"lost", r.lost},
       {"photons", r.photons}};
}

SlabResult run_reference_slab(gpu::ClContext& cl, const SlabParams& p) {
  check((p.tau > 0 && p.tau <= 1e6) || (std::isinf(p.tau) && p.tau > 0), "tau",
        "must be in (0, 1e6] or inf");
  check(p.albedo >= 0 && p.albedo <= 1, "albedo", "must be in [0, 1]");
  check(p.g > -1 && p.g < 1, "g", "must be in (-1, 1)");
  check(p.mu0 > 0 && p.mu0 <= 1, "mu0", "must be in (0, 1]");
  check(p.ior >= 1 && p.ior <= 4, "ior", "must be in [1, 4]");
  check(p.photons >= 1000 && p.photons <= 10'000'000'000LL, "photons", "must be in [1000, 1e10]");

  // Enough work items to fill a device; each traces an equal share.
  const int items = 4096;
  const int per_item = static_cast<int>((p.photons + items - 1) / items);
  const double total = double(per_item) * items;
  cl::Buffer tallies(cl.context(), CL_MEM_WRITE_ONLY, sizeof(float) * kTallies * items);
  cl::Kernel k(cl.program(with_cl_library({"kernels/reference/slab.cl"})), "slab_trace");
  float tau = std::isinf(p.tau) ? INFINITY : float(p.tau);
  gpu::set_args(k, tau, float(p.albedo), float(p.g), float(p.mu0), float(p.ior), per_item, p.seed,
                tallies);
  cl.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(items));
  std::vector<float> host(size_t(kTallies) * items);
  cl.queue().enqueueReadBuffer(tallies, CL_TRUE, 0, host.size() * sizeof(float), host.data());

  double sum[kTallies] = {};
  for (int i = 0; i < items; ++i)
    for (int t = 0; t < kTallies; ++t) sum[t] += host[size_t(i) * kTallies + t];
  auto mean = [&](int t) { return sum[t] / total; };
  // Standard error of a sum of per-photon tallies: the variance of R is that of the sum of its
  // parts, taken per photon; parts are exclusive per photon, so their squares add.
  auto std_err = [&](std::initializer_list<int> parts) {
    double m = 0, m2 = 0;
    for (int t : parts) {
      m += mean(t);
      m2 += sum[t + 1] / total;
    }
    return std::sqrt(std::max(0.0, m2 - m * m) / (total - 1));
  };

  SlabResult r;
  r.photons = static_cast<long long>(total);
  double r_front = 0;
  if (p.ior != 1.0) {
    // Same formula as the kernel's fresnel(), in double.
    double eta = 1.0 / p.ior, ci = p.mu0;
    double ct = std::sqrt(1 - eta * eta * (1 - ci * ci));
    double rs = (eta * ci - ct) / (eta * ci + ct), rp = (ci - eta * ct) / (ci + eta * ct);
    r_front = 0.5 * (rs * rs + rp * rp);
  }
  r.R_diffuse = mean(0);
  r.T_diffuse = mean(2);
  r.T_direct = mean(4);
  r.R_specular = r_front + mean(6);
  r.R_single = mean(8);
  r.T_single = mean(10);
  r.lost = mean(12);
  r.R = r.R_diffuse + r.R_specular;
  r.T = r.T_diffuse + r.T_direct;
  r.R_stderr = std_err({0, 6});
  r.T_stderr = std_err({2, 4});
  return r;
}

}  // namespace scatter
