// OpenCL context and in-order queue on one device, and program building from kernels/.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "gpu/cl.hpp"

namespace scatter::gpu {

struct ClDeviceInfo {
  int platform = 0;
  int device = 0;
  std::string platform_name;
  std::string name;
  std::string version;
  std::string type;  // "gpu", "cpu", "accelerator", "other"
  uint64_t global_memory = 0;
  uint64_t max_alloc = 0;
  int compute_units = 0;
  bool fp64 = false;
};

// Every OpenCL device of every platform; empty when no ICD or platform is installed.
std::vector<ClDeviceInfo> list_cl_devices();

class ClContext {
 public:
  // `selector`: "" picks the first GPU, else the first device; "P:D" picks platform P, device D;
  // anything else picks the first device whose name contains it. Throws GpuError when none fits.
  explicit ClContext(const std::string& selector = "");

  // Builds (once per file list and options) the kernel files, concatenated in order
  // ({"kernels/common/rng.cl", "kernels/reference/path.cl"}). Throws GpuError with the
  // compiler's build log when the build fails.
  cl::Program& program(const std::vector<std::string>& paths, const std::string& options = "");

  cl::Context& context() { return context_; }
  cl::CommandQueue& queue() { return queue_; }
  const cl::Device& device() const { return device_; }
  const ClDeviceInfo& info() const { return info_; }

 private:
  ClDeviceInfo info_;
  cl::Device device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  std::map<std::string, cl::Program> programs_;
};

// Sets every argument of `kernel` in order.
template <class... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  cl_uint i = 0;
  (kernel.setArg(i++, args), ...);
}

}  // namespace scatter::gpu
