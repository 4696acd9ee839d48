#include "base/file_util.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {
namespace fs = std::filesystem;

namespace {

// The one atomic write: a temporary file beside `path`, written, flushed to disk and renamed into place.
void WriteBytesAtomic(const fs::path& path, const char* data, size_t size) {
  const fs::path temporary = path.string() + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const auto fail = [&](const char* what, bool opened) {
    const std::string reason = std::strerror(errno);
    if (opened) ::close(fd);
    ::unlink(temporary.c_str());
    throw UserError(
        format("cannot {} '{}': {}; check the free space, the file-size limit (ulimit -f) and the "
               "folder's permissions",
               what, path.string(), reason));
  };
  if (fd < 0) fail("create", false);
  size_t written = 0;
  while (written < size) {
    const ssize_t n = ::write(fd, data + written, size - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write", true);
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) fail("write", true);
  if (::close(fd) != 0) fail("write", false);
  if (::rename(temporary.c_str(), path.c_str()) != 0) fail("write", false);
}

}  // namespace

void WriteFileAtomic(const fs::path& path, std::string_view contents) {
  WriteBytesAtomic(path, contents.data(), contents.size());
}

void WriteBinaryFileAtomic(const fs::path& path, const std::vector<char>& bytes) {
  WriteBytesAtomic(path, bytes.data(), bytes.size());
}

void WriteJsonAtomic(const fs::path& path, const nlohmann::json& value) { WriteFileAtomic(path, value.dump(2) + "\n"); }

std::string ReadTextFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json ReadJsonFile(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw UserError(format("cannot read '{}'", path.string()));
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {  // a syntax error, or a number too large (out_of_range)
    throw UserError(format("'{}' is not valid JSON: {}", path.string(), e.what()));
  }
}

void SyncDirectory(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

std::string LowerExtension(const fs::path& path) {
  std::string extension = path.extension().string();
  if (!extension.empty()) extension.erase(0, 1);
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

bool IsInside(const fs::path& root, const fs::path& path) {
  const fs::path base = root.lexically_normal(), normal = path.lexically_normal();
  return std::mismatch(base.begin(), base.end(), normal.begin(), normal.end()).first == base.end();
}

}  // namespace p2n
