#pragma once
// The ingest stage: validates every photo by decoding it, applies EXIF orientation, optionally downsizes, and
// writes the images the later stages use plus ingest_report.json. Bad files, and copies of a photo already taken,
// are skipped with a named reason. A video (given alone, or in the folder beside others and photos) gives the
// frames ingest_video.h chooses; a video that cannot be decoded whole is an error.

#include <filesystem>
#include <string>
#include <vector>

#include "stages/ingest/ingest_options.h"
#include "stages/stage_results.h"

namespace p2n {

struct InputFiles {
  std::vector<std::filesystem::path> photos, videos;  // each sorted
};

// What ingest reads from the input: the image files of a folder (jpg, jpeg, png, tif, tiff, exr; any case; not
// hidden) and its videos (IsVideoFile), or the one video given. UserError when the input is missing, is a file
// other than a video, or a folder with neither.
InputFiles ListInputs(const std::filesystem::path& input);

class IngestStage : public StageOf<IngestResult> {
 public:
  // 2: 8-bit output, copies skipped, CMYK re-encoded; 3: cameras, videos.
  int format_version() const override { return 3; }
  // "image NAME" or "video NAME" -> SHA-1 of the file's bytes, for every photo and video of the input.
  std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const override;
  void Run(StageContext& context) const override;
  void CheckResult(const std::filesystem::path& result_dir, const Config& config) const override;
};

}  // namespace p2n
