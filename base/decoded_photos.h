#pragma once
// Photos decoded once into one file, read back a photo at a time: what a PhotoWindow reads instead of decoding a
// PNG or JPEG again each time a photo comes back into it (docs/benchmarks.md has what that saves). The file has no
// name: it is removed from its folder as soon as it is made, so its space returns when it is closed, even when the
// process is killed.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

namespace p2n {

class DecodedPhotos {
 public:
  // Decodes photo i (of sizes[i] bytes) with decode(i), in parallel, into a file in `folder`; UserError naming the
  // folder when it cannot be written (a full disk: the photos' size in all is said).
  DecodedPhotos(const std::filesystem::path& folder, const std::vector<size_t>& sizes,
                const std::function<std::vector<uint8_t>(size_t)>& decode);
  ~DecodedPhotos();
  DecodedPhotos(const DecodedPhotos&) = delete;
  DecodedPhotos& operator=(const DecodedPhotos&) = delete;

  // Photo i's bytes (thread-safe).
  std::vector<uint8_t> Read(size_t i) const;

 private:
  std::filesystem::path folder_;
  int fd_ = -1;
  std::vector<uint64_t> offsets_;  // photo i at [offsets_[i], offsets_[i + 1])
};

}  // namespace p2n
