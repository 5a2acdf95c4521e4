// scatter-load: scripted clients for scatterd, with one JSON report on stdout.
//
//   scatter-load live [--sessions N] [--path orbit|random-walk|burst] [--rate HZ] [--frames N] ...
//   scatter-load rest [--clients N] [--ops render,bake] [--cycles N] ...
//
// Exit status: 0 when the run was made and reported (refusals and server errors are counted in
// the report), 1 when it could not be made (daemon unreachable, token refused), CLI11's codes
// for bad options.
#include <CLI/CLI.hpp>
#include <iostream>

#include "tools/load/load_run.hpp"

namespace {

using scatter::load::LoadOptions;

// --set KEY=VALUE: the value as JSON when it is a number, boolean or null; else a string.
void add_setting(LoadOptions& o, const std::string& kv) {
  auto eq = kv.find('=');
  nlohmann::json v = nlohmann::json::parse(kv.substr(eq + 1), nullptr, false);
  o.settings[kv.substr(0, eq)] =
      v.is_discarded() || v.is_structured() ? nlohmann::json(kv.substr(eq + 1)) : v;
}

void add_common(CLI::App& app, LoadOptions& o, std::vector<std::string>& sets) {
  app.add_option("--host", o.host, "Daemon host")->capture_default_str();
  app.add_option("--port", o.port, "Daemon port")
      ->capture_default_str()
      ->check(CLI::Range(1, 65535));
  app.add_option("--token", o.token, "Sent as \"Authorization: Bearer TOKEN\"");
  app.add_option("--scene", o.scene, "Scene name (scene_name)")->capture_default_str();
  app.add_option("--pipeline", o.pipeline, "Pipeline")->capture_default_str();
  app.add_option("--terms", o.terms, "Terms (default: the pipeline's)");
  app.add_option("--set", sets, "A pipeline setting KEY=VALUE (repeatable)")
      ->check([](const std::string& kv) {
        auto eq = kv.find('=');
        return eq == std::string::npos || eq == 0
                   ? std::string("expected KEY=VALUE, got \"" + kv + "\"")
                   : std::string();
      });
  app.add_option("--duration", o.duration_s, "Seconds to run (0: until --frames/--cycles)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 7 * 86400.0));
  app.add_option("--rss-interval", o.rss_interval_s, "Seconds between RSS samples from /metrics")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 3600.0));
  app.add_option("--pid", o.pid, "Daemon pid: RSS from /proc when /metrics lacks it")
      ->check(CLI::PositiveNumber);
  app.add_option("--timeout", o.timeout_s,
                 "Seconds for connect, handshake and one request; a "
                 "session silent this long gives up")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 86400.0));
}

void add_live(CLI::App& live, LoadOptions& o) {
  live.add_option("--sessions", o.sessions, "Concurrent WebSocket sessions")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  live.add_option("--path", o.path, "Camera path")
      ->capture_default_str()
      ->check(CLI::IsMember({"orbit", "random-walk", "burst"}));
  live.add_option("--rate", o.rate_hz, "Camera messages per second per session")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  live.add_option("--frames", o.frames,
                  "Frames per session (images and failed frames), then close (0: no bound)")
      ->capture_default_str()
      ->check(CLI::Range(0LL, 1000000000LL));
  live.add_option("--format", o.format, "Frame format")
      ->capture_default_str()
      ->check(CLI::IsMember({"jpg", "png"}));
  live.add_option("--orbit-deg-s", o.orbit_deg_s, "Orbit speed (orbit, burst)")
      ->capture_default_str()
      ->check(CLI::Range(-3600.0, 3600.0));
  live.add_option("--burst-poses", o.burst_poses, "Poses per burst")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  live.add_option("--burst-pause-ms", o.burst_pause_ms, "Pause between bursts")
      ->capture_default_str()
      ->check(CLI::Range(0, 3600000));
  live.add_option("--light-every", o.light_every, "A lights message after every N poses (0: never)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  live.add_option("--seed", o.seed, "Random walk seed")->capture_default_str();
}

void add_rest(CLI::App& rest, LoadOptions& o) {
  rest.add_option("--clients", o.clients, "Concurrent REST clients")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  rest.add_option("--ops", o.ops, "What each cycle does: render, bake or both (render,bake)")
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::IsMember({"render", "bake"}));
  rest.add_option("--cycles", o.cycles, "Cycles per client (0: until --duration)")
      ->capture_default_str()
      ->check(CLI::Range(0LL, 1000000000LL));
  rest.add_option("--format", o.format, "Render format")
      ->capture_default_str()
      ->check(CLI::IsMember({"png", "jpg", "exr", "json"}));
  rest.add_option("--poll-ms", o.poll_ms, "Bake status polling interval")
      ->capture_default_str()
      ->check(CLI::Range(1, 60000));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "scatter-load: scripted live (WebSocket) and REST clients for scatterd; prints one JSON "
      "report"};
  LoadOptions o;
  std::vector<std::string> sets;
  add_common(app, o, sets);
  app.fallthrough();  // the common options may follow the mode
  CLI::App* live =
      app.add_subcommand("live", "Concurrent live sessions on /api/ws following a camera path");
  CLI::App* rest =
      app.add_subcommand("rest", "Concurrent clients of POST /api/render and bake jobs");
  add_live(*live, o);
  add_rest(*rest, o);
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  for (const auto& kv : sets) add_setting(o, kv);
  bool bounded = live->parsed() ? o.frames > 0 : o.cycles > 0;
  if (app.count("--duration") == 0 && bounded) o.duration_s = 0;  // the count bounds it alone
  if (o.duration_s == 0 && !bounded) {
    std::cerr << "scatter-load: error: --duration 0 needs "
              << (live->parsed() ? "--frames" : "--cycles") << "\n";
    return 2;
  }
  try {
    scatter::load::LoadRun run(o);
    std::cout << (live->parsed() ? run.live() : run.rest()).dump(2) << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "scatter-load: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
