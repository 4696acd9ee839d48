#include "pipeline/hash.h"

#include <OpenImageIO/hash.h>
#include <tbb/parallel_for.h>

#include <fstream>
#include <vector>

#include "base/errors.h"

namespace p2n {

struct Hasher::Impl {
  OIIO::SHA1 sha1;
  bool finished = false;
};

Hasher::Hasher() : impl_(std::make_unique<Impl>()) {}
Hasher::~Hasher() = default;

Hasher& Hasher::Bytes(const void* data, size_t size) {
  P2N_CHECK(!impl_->finished, "Hasher used after HexDigest()");
  impl_->sha1.append(data, size);
  return *this;
}

Hasher& Hasher::Field(std::string_view value) {
  const uint64_t size = value.size();
  Bytes(&size, sizeof(size));
  return Bytes(value.data(), value.size());
}

Hasher& Hasher::Field(int64_t value) { return Field(std::to_string(value)); }

std::string Hasher::HexDigest() {
  P2N_CHECK(!impl_->finished, "HexDigest() called twice");
  impl_->finished = true;
  return impl_->sha1.digest();
}

std::string Sha1Hex(std::string_view data) { return Hasher().Bytes(data.data(), data.size()).HexDigest(); }

std::string Sha1OfFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UserError("cannot read '" + path.string() + "': check that it exists and is readable");
  Hasher hasher;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    hasher.Bytes(buffer.data(), static_cast<size_t>(in.gcount()));
  }
  if (in.bad()) throw UserError("error while reading '" + path.string() + "'");
  return hasher.HexDigest();
}

std::vector<std::string> Sha1OfFiles(const std::vector<std::filesystem::path>& paths) {
  std::vector<std::string> digests(paths.size());
  tbb::parallel_for(size_t{0}, paths.size(), [&](size_t i) { digests[i] = Sha1OfFile(paths[i]); });
  return digests;
}

}  // namespace p2n
