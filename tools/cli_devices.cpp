// scatterd devices [--json]: the OpenCL devices and the OpenGL renderer this machine offers.
#include <iostream>
#include <nlohmann/json.hpp>

#include "gpu/gpu.hpp"
#include "tools/commands.hpp"

namespace scatter::tools {
namespace {

int run_devices(bool json) {
  auto devices = gpu::list_cl_devices();
  nlohmann::json cl = nlohmann::json::array();
  for (const auto& d : devices)
    cl.push_back({{"id", std::to_string(d.platform) + ":" + std::to_string(d.device)},
                  {"platform", d.platform_name},
                  {"name", d.name},
                  {"version", d.version},
                  {"type", d.type},
                  {"global_memory", d.global_memory},
                  {"max_alloc", d.max_alloc},
                  {"compute_units", d.compute_units},
                  {"fp64", d.fp64}});
  nlohmann::json gl;
  try {
    gpu::GlContext ctx;
    gl = {{"renderer", ctx.renderer()}, {"version", ctx.version()}, {"platform", ctx.platform()}};
  } catch (const gpu::GpuError& e) {
    gl = {{"error", e.what()}};
  }
  if (json) {
    std::cout << nlohmann::json{{"opencl", cl}, {"opengl", gl}}.dump(2) << "\n";
    return 0;
  }
  std::cout << "OpenCL devices:\n";
  if (devices.empty()) std::cout << "  none (install an OpenCL driver, e.g. pocl-opencl-icd)\n";
  for (const auto& d : cl)
    std::cout << "  " << d["id"].get<std::string>() << "  " << d["name"].get<std::string>() << " ["
              << d["type"].get<std::string>() << ", " << d["version"].get<std::string>() << ", "
              << d["global_memory"].get<uint64_t>() / (1 << 20) << " MiB, fp64 "
              << (d["fp64"].get<bool>() ? "yes" : "no") << "]\n";
  std::cout << "OpenGL:\n  ";
  if (gl.contains("error"))
    std::cout << "unavailable: " << gl["error"].get<std::string>() << "\n";
  else
    std::cout << gl["renderer"].get<std::string>() << " (" << gl["version"].get<std::string>()
              << ", EGL " << gl["platform"].get<std::string>() << ")\n";
  return 0;
}

}  // namespace

Handler add_devices_command(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("devices", "List OpenCL devices and the OpenGL renderer");
  cmd->add_flag("--json", *json, "Print JSON");
  return [json] { return run_devices(*json); };
}

}  // namespace scatter::tools
