#pragma once
// The ingest stage: validates every photo by decoding it, applies EXIF orientation, optionally downsizes, and
// writes the images the later stages use plus ingest_report.json. Bad files, and copies of a photo already taken,
// are skipped with a named reason.

#include <filesystem>
#include <string>
#include <vector>

#include "stages/stage_results.h"

namespace p2n {

struct IngestOptions {
  static constexpr const char* kSection = "ingest";  // its options are ingest.NAME

  int max_image_size = 0;  // Longest image side after downsizing (area filter), in pixels; 0 keeps the size.
  int min_images = 3;      // Fewer usable images than this is an error.

  template <class V>
  void Visit(V& v) {
    v("max_image_size", max_image_size, "longest image side after downsizing (area filter); 0 keeps the size", "px");
    v("min_images", min_images, "fewer usable images than this is an error", "images", OptionKind::kCheck);
  }
  void Check() const;
};

// Image files of the folder that ingest reads (jpg, jpeg, png, tif, tiff, exr; any case; not hidden), sorted.
// UserError when the folder is missing, is a file, or has none.
std::vector<std::filesystem::path> ListPhotos(const std::filesystem::path& folder);

class IngestStage : public StageOf<IngestResult> {
 public:
  int format_version() const override { return 2; }  // 2: 8-bit output, copies skipped, CMYK re-encoded
  // "image NAME" -> SHA-1 of the file's bytes, for every photo of the input folder.
  std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const override;
  void Run(StageContext& context) const override;
  void CheckResult(const std::filesystem::path& result_dir, const Config& config) const override;
};

}  // namespace p2n
