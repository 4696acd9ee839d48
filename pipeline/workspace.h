#pragma once
// A workspace folder: one sub-folder per stage, the resolved config, the logs, and a lock.
//
//   WS/workspace.json      marker: format version, the input folder
//   WS/config.json         the resolved configuration of the last run (options given once are remembered)
//   WS/logs/photo2nerf.log the log of every run
//   WS/<stage>/            a complete stage result, manifest.json written last
//   WS/<stage>.partial/    a stage being written (or interrupted); never read as a result
//   WS/<stage>.resume/     what a long stage keeps to resume after a kill (training checkpoints), removed
//                          once the stage completes

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace p2n {

class Workspace {
 public:
  // Opens the workspace at `root`. With `create`, a missing folder is created and an empty folder becomes a
  // workspace. UserError when the path is a file, a folder that is not a photo2nerf workspace and not empty
  // (nothing the user had is touched), missing (without `create`), or not writable.
  static Workspace Open(const std::filesystem::path& root, bool create);

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path StageDir(std::string_view folder) const { return root_ / folder; }
  std::filesystem::path StagingDir(std::string_view folder) const;
  std::filesystem::path TrashDir(std::string_view folder) const;
  std::filesystem::path ResumeDir(std::string_view folder) const;
  std::filesystem::path LogDir() const { return root_ / "logs"; }
  std::filesystem::path ConfigPath() const { return root_ / "config.json"; }
  // The options set for this workspace, applied to every later command in it.
  std::filesystem::path RememberedOptionsPath() const { return root_ / "options.json"; }

  // The photo folder (or dataset) this workspace was made from, as an absolute path.
  std::optional<std::filesystem::path> input() const { return input_; }
  void SetInput(const std::filesystem::path& input);

 private:
  explicit Workspace(std::filesystem::path root) : root_(std::move(root)) {}
  void WriteMarker() const;

  std::filesystem::path root_;
  std::optional<std::filesystem::path> input_;
};

// An exclusive lock on a workspace for the lifetime of the object (flock: released even on SIGKILL).
// UserError naming the other process when the workspace is in use.
class WorkspaceLock {
 public:
  WorkspaceLock(const Workspace& workspace, std::string_view command);
  ~WorkspaceLock();
  WorkspaceLock(const WorkspaceLock&) = delete;
  WorkspaceLock& operator=(const WorkspaceLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace p2n
