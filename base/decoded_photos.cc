#include "base/decoded_photos.h"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {

DecodedPhotos::DecodedPhotos(const std::filesystem::path& folder, const std::vector<size_t>& sizes,
                             const std::function<std::vector<uint8_t>(size_t)>& decode)
    : folder_(folder) {
  offsets_.push_back(0);
  for (const size_t size : sizes) offsets_.push_back(offsets_.back() + size);
  const auto fail = [&](const std::string& what) {
    throw UserError(format("cannot {} the decoded photos ({:.0f} MB in all) in '{}': {}; check the free space there",
                           what, offsets_.back() / 1048576.0, folder_.string(), std::strerror(errno)));
  };
  std::string name = (folder / "decoded_photos.XXXXXX").string();
  fd_ = ::mkstemp(name.data());
  if (fd_ < 0) fail("make a file for");
  ::unlink(name.c_str());  // nameless from now on: nothing is left behind
  try {
    tbb::parallel_for(size_t{0}, sizes.size(), [&](size_t i) {
      const std::vector<uint8_t> pixels = decode(i);
      if (pixels.size() != sizes[i]) throw std::invalid_argument(format("photo {} decoded to another size", i));
      size_t written = 0;
      while (written < pixels.size()) {
        const ssize_t n = ::pwrite(fd_, pixels.data() + written, pixels.size() - written, offsets_[i] + written);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) fail("write");
        written += static_cast<size_t>(n);
      }
    });
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

DecodedPhotos::~DecodedPhotos() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<uint8_t> DecodedPhotos::Read(size_t i) const {
  std::vector<uint8_t> pixels(offsets_.at(i + 1) - offsets_[i]);
  size_t done = 0;
  while (done < pixels.size()) {
    const ssize_t n = ::pread(fd_, pixels.data() + done, pixels.size() - done, offsets_[i] + done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw UserError(format("cannot read the decoded photos back from '{}': {}", folder_.string(),
                             n < 0 ? std::strerror(errno) : "the file is shorter than written"));
    }
    done += static_cast<size_t>(n);
  }
  return pixels;
}

}  // namespace p2n
