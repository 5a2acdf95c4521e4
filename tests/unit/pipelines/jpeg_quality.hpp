// The quality (libjpeg's 1-100 scale) a JPEG was encoded at, read back from its first
// quantization table: the q whose scaled standard luminance table (the JPEG standard's Annex K,
// as libjpeg scales it) has the same sum. For tests of what quality an encoder was asked for.
#pragma once

#include <algorithm>
#include <array>
#include <cstdlib>
#include <optional>
#include <string>

namespace scatter::test {

inline std::optional<int> jpeg_quality(const std::string& jpeg) {
  static constexpr std::array<int, 64> kLuma = {
      16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
      14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
      18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
      49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
  auto byte = [&](size_t i) { return static_cast<unsigned char>(jpeg[i]); };
  for (size_t i = 2; i + 4 + 64 < jpeg.size(); ++i) {
    if (byte(i) != 0xFF || byte(i + 1) != 0xDB) continue;  // DQT
    if (byte(i + 4) >> 4) return std::nullopt;             // 16-bit entries: not libjpeg's
    int sum = 0;
    for (size_t k = 0; k < 64; ++k) sum += byte(i + 5 + k);
    std::optional<int> best;
    int best_diff = 1 << 30;
    for (int q = 1; q <= 100; ++q) {
      int scale = q < 50 ? 5000 / q : 200 - 2 * q, scaled = 0;
      for (int v : kLuma) scaled += std::clamp((v * scale + 50) / 100, 1, 255);
      if (std::abs(scaled - sum) < best_diff) best_diff = std::abs(scaled - sum), best = q;
    }
    return best;
  }
  return std::nullopt;
}

}  // namespace scatter::test
