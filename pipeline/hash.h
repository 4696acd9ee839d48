#pragma once
// Stable content hashes (SHA-1, hex): the same bytes give the same digest on every platform and version.
// Never std::hash (docs/design.md §2).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace p2n {

// Incremental SHA-1. Field() frames each value with its length, so ("ab","c") and ("a","bc") differ.
class Hasher {
 public:
  Hasher();
  ~Hasher();
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;

  Hasher& Bytes(const void* data, size_t size);
  Hasher& Field(std::string_view value);
  Hasher& Field(int64_t value);
  // The hex digest; the hasher cannot be used afterwards.
  std::string HexDigest();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

std::string Sha1Hex(std::string_view data);

// SHA-1 of a file's bytes (streamed). Throws UserError naming the file when it cannot be read.
std::string Sha1OfFile(const std::filesystem::path& path);
// Sha1OfFile of each file, hashed in parallel, in the same order.
std::vector<std::string> Sha1OfFiles(const std::vector<std::filesystem::path>& paths);

}  // namespace p2n
