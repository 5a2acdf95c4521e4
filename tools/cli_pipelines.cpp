// scatterd pipelines [--json] [--markdown NAME]: every pipeline the registry holds, its terms and
// its settings table (the same data as GET /api/pipelines); --markdown prints one pipeline's
// settings table as docs/pipelines/NAME.md holds it.
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "pipelines/registry.hpp"
#include "tools/commands.hpp"

namespace scatter::tools {
namespace {

struct PipelinesOptions {
  bool json = false;
  std::string markdown;
};

int run_pipelines(const PipelinesOptions& o) {
  if (!o.markdown.empty()) {
    std::cout << settings_markdown(pipeline_info(o.markdown));
    return 0;
  }
  if (o.json) {
    nlohmann::json list = nlohmann::json::array();
    for (const PipelineInfo* p : registry()) list.push_back(*p);
    std::cout << nlohmann::json{{"pipelines", list}}.dump(2) << "\n";
    return 0;
  }
  std::cout << std::setprecision(10);
  for (const PipelineInfo* p : registry()) {
    std::string terms;
    for (Terms t : p->terms) terms += (terms.empty() ? "" : ", ") + to_string(t);
    std::cout << p->name << ": " << p->summary << "\n  terms: " << terms << " (default "
              << to_string(p->default_terms) << ")" << (p->bakes() ? "; bakes" : "") << "\n";
    for (const SettingInfo& s : p->settings)
      std::cout << "  " << s.key << " = " << s.def << "  [" << s.lo << ", " << s.hi << "] "
                << to_string(s.kind) << ", shapes " << to_string(s.shapes.what) << ": " << s.doc
                << "\n";
  }
  return 0;
}

}  // namespace

Handler add_pipelines_command(CLI::App& app) {
  auto o = std::make_shared<PipelinesOptions>();
  CLI::App* cmd = app.add_subcommand("pipelines", "List the pipelines, their terms and settings");
  cmd->add_flag("--json", o->json, "Print JSON (as GET /api/pipelines)");
  cmd->add_option("--markdown", o->markdown, "Print this pipeline's settings table in Markdown");
  return [o] { return run_pipelines(*o); };
}

}  // namespace scatter::tools
