// The scatterd verbs. Each registers its options on the CLI11 app and returns the handler that
// runs it; handlers throw on error and main() turns that into one line on stderr.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace scatter::tools {

using Handler = std::function<int()>;

Handler add_render_command(CLI::App& app);
Handler add_devices_command(CLI::App& app);
Handler add_slab_command(CLI::App& app);
Handler add_bench_command(CLI::App& app);
Handler add_serve_command(CLI::App& app);
Handler add_bake_command(CLI::App& app);
Handler add_beam_command(CLI::App& app);
Handler add_pipelines_command(CLI::App& app);

}  // namespace scatter::tools
