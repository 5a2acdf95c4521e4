// scatterd: the scatter daemon and its one-shot verbs (render, bake, slab, bench, devices,
// pipelines).
#include <spdlog/spdlog.h>

#include <iostream>
#include <map>

#include "tools/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"scatter: rendering of translucent and participating media"};
  app.require_subcommand(1);
  app.fallthrough();  // --log-level also after the verb
  std::string log_level = "warn";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));

  std::map<CLI::App*, scatter::tools::Handler> handlers;
  auto add = [&](scatter::tools::Handler (*f)(CLI::App&)) {
    std::size_t before = app.get_subcommands({}).size();
    auto handler = f(app);
    handlers[app.get_subcommands({}).at(before)] = handler;
  };
  add(&scatter::tools::add_render_command);
  add(&scatter::tools::add_devices_command);
  add(&scatter::tools::add_slab_command);
  add(&scatter::tools::add_bench_command);
  add(&scatter::tools::add_serve_command);
  add(&scatter::tools::add_bake_command);
  add(&scatter::tools::add_beam_command);
  add(&scatter::tools::add_pipelines_command);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  spdlog::set_default_logger(spdlog::default_logger()->clone("scatterd"));
  // One line per event: time, level, then the event's key=value fields.
  spdlog::set_pattern("ts=%Y-%m-%dT%H:%M:%S.%e level=%l %v");
  spdlog::set_level(spdlog::level::from_str(log_level));
  try {
    for (auto* sub : app.get_subcommands())
      if (auto it = handlers.find(sub); it != handlers.end()) return it->second();
  } catch (const std::exception& e) {
    std::cerr << "scatterd: error: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
