// scatterd serve [--bind ADDR] [--port N] [--token T] [--scenes-dir DIR] [--max-upload-mb N]
//                [--max-image N] [--max-sessions N] [--device D] [--cache-dir DIR]
#include <spdlog/spdlog.h>

#include <iostream>

#include "server/server.hpp"
#include "tools/cache_option.hpp"
#include "tools/commands.hpp"

#ifndef SCATTER_SCENES_DIR
#define SCATTER_SCENES_DIR "scenes"
#endif

namespace scatter::tools {
namespace {

struct ServeOptions {
  server::ServerOptions server;
  std::string scenes_dir = SCATTER_SCENES_DIR;
  CacheOptions cache;
};

int run_serve(ServeOptions o) {
  o.server.api.scenes_dir = o.scenes_dir;
  if (!std::filesystem::is_directory(o.server.api.scenes_dir))
    throw std::runtime_error("--scenes-dir: " + o.scenes_dir + " is not a folder");
  o.server.cache = open_cache(o.cache);
  if (!o.server.cache->dir().empty()) o.server.api.assets_dir = o.server.cache->dir() / "assets";
  server::Server server(o.server);
  std::cout << "scatterd: serving on http://" << o.server.bind << ":" << server.port() << "/"
            << std::endl;
  server.run(true);
  std::cout << "scatterd: stopped" << std::endl;
  return 0;
}

}  // namespace

Handler add_serve_command(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand("serve", "Serve the REST API (renders, devices, metrics)");
  cmd->add_option("--bind", o->server.bind, "Address to listen on")->capture_default_str();
  cmd->add_option("--port", o->server.port, "Port (0: any free port)")->capture_default_str();
  cmd->add_option("--token", o->server.api.token, "Require \"Authorization: Bearer TOKEN\"");
  cmd->add_option("--scenes-dir", o->scenes_dir, "Shipped scenes, and base of relative mesh paths")
      ->capture_default_str();
  cmd->add_option("--max-upload-mb", o->server.max_upload_mb, "Largest request body")
      ->capture_default_str()->check(CLI::Range(1, 4096));
  cmd->add_option("--max-image", o->server.api.max_image, "Largest image side a request may ask")
      ->capture_default_str()->check(CLI::Range(16, 8192));
  cmd->add_option("--max-sessions", o->server.api.max_sessions, "Live WebSocket sessions at once")
      ->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--device", o->server.gpu.cl_device, "OpenCL device: P:D or part of its name");
  add_cache_options(cmd, o->cache);
  return [o] { return run_serve(*o); };
}

}  // namespace scatter::tools
