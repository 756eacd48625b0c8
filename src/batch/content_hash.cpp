#include "batch/content_hash.h"

#include <openssl/evp.h>

#include <fstream>
#include <memory>
#include <vector>

#include "core/error.h"
#include "core/view_set.h"

namespace u3d {
namespace {

std::string hex(const unsigned char* bytes, unsigned size) {
  static const char digits[] = "0123456789abcdef";
  std::string text;
  for (unsigned i = 0; i < size; ++i) {
    text += digits[bytes[i] >> 4];
    text += digits[bytes[i] & 15];
  }
  return text;
}

class Sha256 {
 public:
  Sha256() : ctx_(EVP_MD_CTX_new(), EVP_MD_CTX_free) {
    require(ctx_ && EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) == 1, "SHA-256 is not available (OpenSSL)");
  }
  void update(const void* data, size_t size) { EVP_DigestUpdate(ctx_.get(), data, size); }
  std::string hex_digest() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned size = 0;
    EVP_DigestFinal_ex(ctx_.get(), digest, &size);
    return hex(digest, size);
  }

 private:
  std::unique_ptr<EVP_MD_CTX, void (*)(EVP_MD_CTX*)> ctx_;
};

}  // namespace

std::string sha256_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  require(bool(in), "cannot read " + path.string());
  Sha256 sha;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    sha.update(buffer.data(), size_t(in.gcount()));
  }
  require(in.eof(), "cannot read " + path.string());
  return sha.hex_digest();
}

std::string input_hash(const BatchInput& input) {
  if (input.mode == BatchMode::Generate) return sha256_file(input.path);
  Sha256 sha;
  for (View v : kAllViews)
    for (bool normal : {false, true}) {
      const std::string name = view_file_name(v, normal);
      const std::string line = name + " " + sha256_file(input.path / name) + "\n";
      sha.update(line.data(), line.size());
    }
  return sha.hex_digest();
}

}  // namespace u3d
