#include "gpu/cl_context.hpp"

#include "gpu/embedded_sources.hpp"

namespace scatter::gpu {
namespace {

std::vector<cl::Platform> platforms() {
  std::vector<cl::Platform> list;
  try {
    cl::Platform::get(&list);
  } catch (const cl::Error&) {
    // The ICD loader reports "no platform" as an error (CL_PLATFORM_NOT_FOUND_KHR).
    list.clear();
  }
  return list;
}

std::string type_name(cl_device_type t) {
  if (t & CL_DEVICE_TYPE_GPU) return "gpu";
  if (t & CL_DEVICE_TYPE_CPU) return "cpu";
  if (t & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
  return "other";
}

ClDeviceInfo describe(int p, int d, const cl::Platform& platform, const cl::Device& device) {
  ClDeviceInfo info;
  info.platform = p;
  info.device = d;
  info.platform_name = platform.getInfo<CL_PLATFORM_NAME>();
  info.name = device.getInfo<CL_DEVICE_NAME>();
  info.version = device.getInfo<CL_DEVICE_VERSION>();
  info.type = type_name(device.getInfo<CL_DEVICE_TYPE>());
  info.global_memory = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
  info.max_alloc = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
  info.compute_units = static_cast<int>(device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
  info.fp64 = device.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_khr_fp64") != std::string::npos;
  return info;
}

template <class F>
void each_device(F f) {
  auto plats = platforms();
  for (size_t p = 0; p < plats.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      plats[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;  // a platform with no devices reports CL_DEVICE_NOT_FOUND
    }
    for (size_t d = 0; d < devices.size(); ++d)
      f(static_cast<int>(p), static_cast<int>(d), plats[p], devices[d]);
  }
}

}  // namespace

std::vector<ClDeviceInfo> list_cl_devices() {
  std::vector<ClDeviceInfo> out;
  each_device([&](int p, int d, const cl::Platform& pl, const cl::Device& dev) {
    out.push_back(describe(p, d, pl, dev));
  });
  return out;
}

ClContext::ClContext(const std::string& selector) {
  std::vector<std::pair<ClDeviceInfo, cl::Device>> all;
  each_device([&](int p, int d, const cl::Platform& pl, const cl::Device& dev) {
    all.emplace_back(describe(p, d, pl, dev), dev);
  });
  if (all.empty())
    throw GpuError("no OpenCL device found: install an OpenCL driver (on Debian: pocl-opencl-icd)");
  const std::pair<ClDeviceInfo, cl::Device>* pick = nullptr;
  for (const auto& cand : all) {
    const ClDeviceInfo& i = cand.first;
    bool match = selector.empty()
                     ? i.type == "gpu"
                     : (selector == std::to_string(i.platform) + ":" + std::to_string(i.device) ||
                        i.name.find(selector) != std::string::npos);
    if (match) {
      pick = &cand;
      break;
    }
  }
  if (!pick && selector.empty()) pick = &all.front();
  if (!pick)
    throw GpuError("no OpenCL device matches \"" + selector +
                   "\"; list them with 'scatterd devices'");
  info_ = pick->first;
  device_ = pick->second;
  try {
    context_ = cl::Context(device_);
    queue_ = cl::CommandQueue(context_, device_);
  } catch (const cl::Error& e) {
    throw GpuError("cannot create an OpenCL context on " + info_.name + ": " + e.what() + " (" +
                   std::to_string(e.err()) + ")");
  }
}

cl::Program& ClContext::program(const std::vector<std::string>& paths, const std::string& options) {
  std::string key = options, source, path;
  for (const auto& p : paths) {
    key += "\n" + p;
    path += (path.empty() ? "" : " + ") + p;
  }
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;
  for (const auto& p : paths) source.append(embedded_source(p)).append("\n");
  cl::Program program(context_, source);
  try {
    program.build({device_}, (options + " -cl-std=CL1.2").c_str());
  } catch (const cl::Error&) {
    std::string log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_);
    throw GpuError("OpenCL build of " + path + " failed:\n" + log);
  }
  return programs_.emplace(key, std::move(program)).first->second;
}

}  // namespace scatter::gpu
