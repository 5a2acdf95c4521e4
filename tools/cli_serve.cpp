// scatterd serve [--bind ADDR] [--port N] [--token T] [--no-token] [--scenes-dir DIR]
//                [--max-upload-mb N] [--max-image N] [--max-sessions N] [--max-request-mb MB]
//                [--max-render-s S] [--session-idle-s S] [--max-queue N] [--device D] [--cache-dir
//                DIR]
#include <spdlog/spdlog.h>

#include <cstdlib>
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
  bool token_given = false, no_token = false;
};

bool is_loopback(const std::string& bind) {
  boost::system::error_code ec;
  auto a = boost::asio::ip::make_address(bind, ec);
  return !ec && a.is_loopback();
}

int run_serve(ServeOptions o) {
  if (o.token_given && o.server.api.token.empty())
    throw std::runtime_error(
        "--token: is empty; give a secret, or --no-token to serve without one");
  if (!o.token_given && !o.no_token && !is_loopback(o.server.bind))
    throw std::runtime_error("--bind " + o.server.bind +
                             " serves beyond this machine: give --token T "
                             "(or $SCATTER_TOKEN), or --no-token to serve without authentication");
  o.server.api.scenes_dir = o.scenes_dir;
  if (!std::filesystem::is_directory(o.server.api.scenes_dir))
    throw std::runtime_error("--scenes-dir: " + o.scenes_dir + " is not a folder");
  o.server.cache = open_cache(o.cache);
  if (!o.server.cache->dir().empty()) o.server.api.assets_dir = o.server.cache->dir() / "assets";
  server::Server server(o.server);
  std::cout << "scatterd: serving on http://" << o.server.bind << ":" << server.port() << "/"
            << std::endl;
  server.run(true);
  // Queued work was dropped and running work cancelled; run() waited up to Server::kStopGrace
  // for it (and as long again for the answers owed), so a pipeline step that cannot be
  // interrupted does not hold the exit past that.
  if (!server.wait_stopped(std::chrono::milliseconds(0))) {
    spdlog::warn("event=stop_timeout grace_ms={} action=exit_without_waiting",
                 server::Server::kStopGrace.count());
    std::cout << "scatterd: stopped (a render was still running)" << std::endl;
    std::_Exit(0);
  }
  std::cout << "scatterd: stopped" << std::endl;
  return 0;
}

}  // namespace

Handler add_serve_command(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand("serve", "Serve the REST API (renders, devices, metrics)");
  cmd->add_option("--bind", o->server.bind, "Address to listen on")->capture_default_str();
  cmd->add_option("--port", o->server.port, "Port (0: any free port)")->capture_default_str();
  cmd->add_option("--token", o->server.api.token,
                  "Require \"Authorization: Bearer TOKEN\" (or ?token=)")
      ->envname("SCATTER_TOKEN")
      ->each([o](const std::string&) { o->token_given = true; });
  cmd->add_flag("--no-token", o->no_token, "Serve without a token on a non-loopback --bind");
  cmd->add_option("--scenes-dir", o->scenes_dir, "Shipped scenes, and base of relative mesh paths")
      ->capture_default_str();
  cmd->add_option("--max-upload-mb", o->server.max_upload_mb, "Largest request body")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--max-image", o->server.api.max_image, "Largest image side a request may ask")
      ->capture_default_str()
      ->check(CLI::Range(16, 8192));
  cmd->add_option("--max-sessions", o->server.api.max_sessions, "Live WebSocket sessions at once")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  cmd->add_option("--max-request-mb", o->server.api.max_request_mb,
                  "Largest estimated host + device memory of one render or bake")
      ->capture_default_str()
      ->check(CLI::Range(16.0, 1e7));
  cmd->add_option("--max-render-s", o->server.api.max_render_s,
                  "Longest estimated (and enforced) time of one render")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1e6));
  cmd->add_option("--session-idle-s", o->server.api.session_idle_s,
                  "A live session that sends nothing for this long is closed")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  cmd->add_option("--refine-pass-s", o->server.api.refine_pass_s,
                  "What one reference pass of a still live view aims to take")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 600.0));
  cmd->add_option("--refine-max-passes", o->server.api.refine_max_passes,
                  "Reference passes that refine a still live view, at most (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--max-queue", o->server.max_queue,
                  "REST renders that may wait for the render thread")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--device", o->server.gpu.cl_device, "OpenCL device: P:D or part of its name");
  add_cache_options(cmd, o->cache);
  return [o] { return run_serve(*o); };
}

}  // namespace scatter::tools
