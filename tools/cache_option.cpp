#include "tools/cache_option.hpp"

namespace scatter::tools {

void add_cache_options(CLI::App* cmd, CacheOptions& o) {
  cmd->add_option("--cache-dir", o.dir,
                  "Directory of cached bake products (default: " +
                      BakeCache::default_dir().string() + "; \"none\": memory only)");
  cmd->add_option("--cache-max-mb", o.max_mb,
                  "Disk budget of the cache directory's products; the least "
                  "recently used go first")
      ->capture_default_str()
      ->check(CLI::Range(size_t(1), size_t(1) << 24));
}

std::unique_ptr<BakeCache> open_cache(const CacheOptions& o) {
  if (o.dir == "none") return std::make_unique<BakeCache>();
  auto cache = std::make_unique<BakeCache>(o.dir.empty() ? BakeCache::default_dir()
                                                         : std::filesystem::path(o.dir));
  cache->set_disk_budget(uint64_t(o.max_mb) << 20);
  return cache;
}

}  // namespace scatter::tools
