// Content-addressed cache of bake products: an LRU in memory in front of checksummed files on
// disk. Keys are SHA-256 hex digests built with BakeKey; products are opaque bytes. Thread safe.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include "protocol/digest.hpp"

namespace scatter {

// Part of every key and of every file header: bump it when a product's or the file's layout
// changes, and old keys (and files) stop matching. 2: the header names the file's key.
inline constexpr uint32_t kBakeFormatVersion = 2;

// True for exactly 64 lowercase hex characters: the only names BakeCache accepts.
bool is_bake_key(std::string_view key_hex);

// Builds a cache key from named parts in order: key = sha256 of a canonical serialisation of the
// (type, name, value) parts, each length-prefixed, after a line naming kBakeFormatVersion.
// Numbers are written as the shortest decimal that reads back to the same double.
class BakeKey {
 public:
  BakeKey& add(std::string_view name, std::string_view value);
  BakeKey& add(std::string_view name, double value);
  BakeKey& add_bytes(std::string_view name, std::string_view bytes);  // hashed first, then added
  std::string hex() const;                                            // 64 hex chars

 private:
  BakeKey& add_part(char type, std::string_view name, std::string_view value);

  std::string parts_;  // the canonical serialisation so far
};

// misses counts every get() that returned nullopt, corrupt ones included.
struct CacheStats {
  uint64_t memory_hits = 0, disk_hits = 0, misses = 0, corrupt = 0, stores = 0;
  uint64_t disk_evictions = 0;  // files removed to keep the directory under its disk budget
};

class BakeCache {
 public:
  // dir empty: memory only. Creates the directory if needed (throws std::runtime_error with the
  // path if it cannot).
  explicit BakeCache(std::filesystem::path dir = {}, size_t memory_budget_bytes = 512u << 20);

  // Returns the product's bytes, or nullopt. Looks in memory, then on disk; a disk file whose
  // header (magic, version, size, this key) or checksum does not verify is counted in
  // stats().corrupt, renamed aside to <key>.corrupt, logged, and reported as a miss so that the
  // caller re-bakes and put()s. Throws std::invalid_argument unless is_bake_key(key_hex).
  std::optional<std::shared_ptr<const std::string>> get(const std::string& key_hex);

  // Stores in memory and (if dir) on disk: written to a temporary file in dir, then renamed over
  // <key>.bake, so readers see the old file or the new one, never half of one. A failed disk write
  // is logged and leaves the memory copy. Throws std::invalid_argument unless is_bake_key(key_hex).
  void put(const std::string& key_hex, std::string bytes);

  CacheStats stats() const;
  // Keeps the directory's .bake files under `bytes` (0: no limit) by removing the least recently
  // used (file modification time; a disk hit refreshes it) after each put(). The scan also removes
  // temporary files a crashed writer left, once they are an hour old.
  void set_disk_budget(uint64_t bytes);
  const std::filesystem::path& dir() const;
  size_t memory_bytes() const;  // payload bytes held in memory now

  // <dir>/<key>.bake; empty when the cache is memory only.
  std::filesystem::path file_path(const std::string& key_hex) const;

  // Default disk directory: $XDG_CACHE_HOME/scatter or $HOME/.cache/scatter (or
  // /tmp/scatter-cache if neither set).
  static std::filesystem::path default_dir();

 private:
  using Product = std::shared_ptr<const std::string>;
  using Lru = std::list<std::pair<std::string, Product>>;  // most recently used first

  void remember(const std::string& key_hex, Product product);  // caller holds mutex_
  void write_file(const std::string& key_hex, const std::string& bytes);
  void trim_disk(const std::string& keep_key);
  // Counts a corrupt file and moves it aside; says what became of it.
  std::string quarantine(const std::filesystem::path& path, uint64_t writes_seen);

  const std::filesystem::path dir_;
  const size_t memory_budget_;
  std::atomic<uint64_t> disk_budget_{0};

  mutable std::mutex mutex_;
  Lru lru_;
  std::unordered_map<std::string, Lru::iterator> index_;
  size_t memory_bytes_ = 0;
  // Files renamed into place: lets get() tell a file written meanwhile from the bad one it read.
  uint64_t disk_writes_ = 0;
  uint64_t temp_counter_ = 0;  // names this process's temporary files apart
  CacheStats stats_;
};

}  // namespace scatter
