#include "tools/cache_option.hpp"

namespace scatter::tools {

void add_cache_dir_option(CLI::App* cmd, std::string& dir) {
  cmd->add_option("--cache-dir", dir,
                  "Directory of cached bake products (default: " + BakeCache::default_dir().string() +
                      "; \"none\": memory only)");
}

std::unique_ptr<BakeCache> open_cache(const std::string& dir) {
  if (dir == "none") return std::make_unique<BakeCache>();
  return std::make_unique<BakeCache>(dir.empty() ? BakeCache::default_dir() : std::filesystem::path(dir));
}

}  // namespace scatter::tools
