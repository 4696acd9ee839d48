#include "pipeline/workspace.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr const char* kMarker = "workspace.json";
constexpr int kWorkspaceFormat = 1;

}  // namespace

Workspace Workspace::Open(const fs::path& root_in, bool create) {
  const fs::path root = fs::absolute(root_in).lexically_normal();
  std::error_code error;
  const fs::file_status status = fs::status(root, error);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw UserError(
        format("workspace '{}' is a file, not a folder; choose a new folder for the workspace", root.string()));
  }
  Workspace workspace(root);
  const fs::path marker = root / kMarker;
  if (fs::exists(marker)) {
    const nlohmann::json meta = ReadJsonFile(marker);
    const int version = meta.value("photo2nerf_workspace", 0);
    if (version != kWorkspaceFormat) {
      throw UserError(format("'{}' has workspace format {}, this photo2nerf reads format {}; use a new workspace",
                             marker.string(), version, kWorkspaceFormat));
    }
    if (meta.contains("input") && meta["input"].is_string()) workspace.input_ = meta["input"].get<std::string>();
    return workspace;
  }
  if (!create) {
    throw UserError(format("'{}' is not a photo2nerf workspace (no {}); create one with `photo2nerf run PHOTOS -w {}`",
                           root.string(), kMarker, root.string()));
  }
  if (fs::exists(status) && !fs::is_empty(root, error)) {
    throw UserError(
        format("'{}' is not empty and is not a photo2nerf workspace; to keep its files safe, choose "
               "a new or empty folder for the workspace",
               root.string()));
  }
  fs::create_directories(root, error);
  if (error) {
    throw UserError(format("cannot create the workspace folder '{}': {}", root.string(), error.message()));
  }
  workspace.WriteMarker();
  return workspace;
}

fs::path Workspace::StagingDir(std::string_view folder) const { return root_ / (std::string(folder) + ".partial"); }
fs::path Workspace::TrashDir(std::string_view folder) const { return root_ / (std::string(folder) + ".old"); }

fs::path Workspace::ResumeDir(std::string_view folder) const { return root_ / (std::string(folder) + ".resume"); }

void Workspace::SetInput(const fs::path& input) {
  input_ = fs::absolute(input).lexically_normal();
  WriteMarker();
}

void Workspace::WriteMarker() const {
  nlohmann::json meta = {{"photo2nerf_workspace", kWorkspaceFormat}};
  if (input_) meta["input"] = input_->string();
  WriteJsonAtomic(root_ / kMarker, meta);
}

WorkspaceLock::WorkspaceLock(const Workspace& workspace, std::string_view command) {
  const fs::path path = workspace.root() / ".lock";
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw UserError(format("cannot create the lock file '{}': {}", path.string(), std::strerror(errno)));
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    char holder[512] = {};
    const ssize_t n = ::pread(fd_, holder, sizeof(holder) - 1, 0);
    std::string who = n > 0 ? std::string(holder, static_cast<size_t>(n)) : "another process";
    while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
    ::close(fd_);
    fd_ = -1;
    throw UserError(format("workspace '{}' is in use by {}; wait for it to finish or stop it first",
                           workspace.root().string(), who));
  }
  const std::string holder = format("process {} ({})\n", ::getpid(), command);
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] ssize_t written = ::pwrite(fd_, holder.data(), holder.size(), 0);
  }
}

WorkspaceLock::~WorkspaceLock() {
  if (fd_ >= 0) {
    [[maybe_unused]] int truncated = ::ftruncate(fd_, 0);
    ::flock(fd_, LOCK_UN);
    ::close(fd_);
  }
}

}  // namespace p2n
