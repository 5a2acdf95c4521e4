#include "protocol/digest.hpp"

#include <openssl/evp.h>

#include <stdexcept>

namespace scatter {

Digest sha256(std::string_view bytes) {
  Digest d;
  unsigned int len = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), d.data(), &len, EVP_sha256(), nullptr) != 1 ||
      len != d.size())
    throw std::runtime_error("SHA-256 failed (OpenSSL EVP_Digest)");
  return d;
}

std::string to_hex(const Digest& d) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * d.size());
  for (unsigned char c : d) {
    hex += kDigits[c >> 4];
    hex += kDigits[c & 15];
  }
  return hex;
}

std::string sha256_hex(std::string_view bytes) {
  return to_hex(sha256(bytes));
}

}  // namespace scatter
