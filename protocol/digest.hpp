// SHA-256 of bytes (OpenSSL EVP): content addresses for assets and bake products.
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace scatter {

using Digest = std::array<unsigned char, 32>;

// Throws std::runtime_error if OpenSSL fails.
Digest sha256(std::string_view bytes);
// Lowercase hex (64 characters for a digest).
std::string to_hex(const Digest& d);
// SHA-256 of bytes, lowercase hex (64 chars).
std::string sha256_hex(std::string_view bytes);

}  // namespace scatter
