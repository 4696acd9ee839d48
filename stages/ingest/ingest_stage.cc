#include "stages/ingest/ingest_stage.h"

#include <OpenImageIO/imagebufalgo.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <set>
#include <variant>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"
#include "base/video_io.h"
#include "formats/image_masks.h"
#include "pipeline/cancel.h"
#include "pipeline/hash.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/ingest/ingest_video.h"
#include "stages/stage_reports.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

const std::string kDuplicateReason = "the same pixels as ";  // a skipped photo's reason

const std::set<std::string> kImageExtensions = {"jpg", "jpeg", "png", "tif", "tiff", "exr"};

fs::path InputFolder(const Workspace& workspace) {
  if (!workspace.input()) {
    throw UserError(format("workspace '{}' has no photo folder yet; run `photo2nerf run PHOTOS -w {}`",
                           workspace.root().string(), workspace.root().string()));
  }
  return *workspace.input();
}

// The masks of the photos (MasksFolder), in their order; none when there is no such folder.
std::vector<fs::path> PhotoMasks(const fs::path& input, const InputFiles& files) {
  const fs::path masks = MasksFolder(input);
  if (files.photos.empty() || masks.empty()) return {};
  if (!files.videos.empty()) {
    throw UserError(
        format("'{}' holds videos beside masks/, whose masks are for photos alone: move the videos to a "
               "folder of their own, or the masks away",
               input.string()));
  }
  return MatchMasks(masks, files.photos);
}

// Writes the photo's mask (`mask`; ReadMask with the photo's EXIF `orientation`) at the size of its image (`image`,
// named `name`) into `masks_dir` under the image's name (PNG whatever the name says: COLMAP's undistorter finds a file
// by its image's name).
void WriteMask(const fs::path& mask, const fs::path& photo, int orientation, const OIIO::ImageSpec& image,
               const fs::path& masks_dir, const std::string& name) {
  const OIIO::ImageBuf alpha = ReadMask(mask, photo, image.width, image.height, orientation);
  if (!alpha.write((masks_dir / name).string(), OIIO::TypeDesc::UINT8, "png"))
    throw UserError(format("cannot write '{}': {}", (masks_dir / name).string(), alpha.geterror()));
}

// Decodes one photo and writes what later stages read, and its mask when it has one. Files that need no change are
// copied byte for byte.
std::variant<IngestedImage, SkippedPhoto> IngestOne(const fs::path& source, const fs::path& mask,
                                                    const IngestResult& out_dirs, const IngestOptions& options) {
  const fs::path images_dir = out_dirs.images();
  const std::string file = source.filename().string();
  ReadImageResult read = ReadImage(source);
  if (!read.ok()) return SkippedPhoto{file, read.error};
  IngestedImage out;
  out.source = file;
  out.orientation = read.orientation;
  out.camera = read.camera;
  OIIO::ImageBuf image = DownsizeAndDescribe(read.image, options.max_image_size, &out);
  const auto name_image = [&](const std::string& name) {
    out.name = name;
    if (!mask.empty()) WriteMask(mask, source, read.orientation, image.spec(), out_dirs.masks(), name);
  };
  const std::string extension = LowerExtension(source);
  out.from_cmyk = read.from_cmyk;
  const bool eight_bit = image.spec().format == OIIO::TypeDesc::UINT8;
  const bool unchanged = read.orientation == 1 && image.spec().width == out.source_width && eight_bit &&
                         !read.from_cmyk && (extension == "jpg" || extension == "jpeg" || extension == "png");
  if (unchanged) {
    name_image(file);
    std::error_code error;
    fs::copy_file(source, images_dir / out.name, fs::copy_options::overwrite_existing, error);
    if (error) throw UserError(format("cannot write '{}': {}", (images_dir / out.name).string(), error.message()));
    return out;
  }
  // Anything else becomes an 8-bit PNG, named after the file and its extension so that names stay unique
  // (a.png, a_tif.png, a_PNG.png). Eight bits because COLMAP does not register 16-bit PNGs (the messy-folder
  // test found it) and training reads 8 bits anyway; HDR (float) images are encoded to sRGB first.
  const std::string original_extension = source.extension().string().substr(1);
  name_image(source.stem().string() + (original_extension == "png" ? "" : "_" + original_extension) + ".png");
  if (image.spec().format == OIIO::TypeDesc::FLOAT) image = OIIO::ImageBufAlgo::colorconvert(image, "linear", "sRGB");
  if (!eight_bit) {
    OIIO::ImageBuf eight(
        OIIO::ImageSpec(image.spec().width, image.spec().height, image.spec().nchannels, OIIO::TypeDesc::UINT8));
    eight.copy_pixels(image);
    image = std::move(eight);
  }
  const std::string error = WriteImage(image, images_dir / out.name);
  if (!error.empty()) throw UserError(error);
  return out;
}

// UserError when the report counts fewer usable images than ingest.min_images.
void CheckImageCount(const IngestReport& report, int min_images) {
  const size_t count = report.images.size();
  if (static_cast<int>(count) >= min_images) return;
  size_t duplicates = 0;
  for (const SkippedPhoto& skip : report.skipped) duplicates += skip.reason.rfind(kDuplicateReason, 0) == 0;
  throw UserError(
      format("only {} usable images in '{}' ({} skipped{}, see the warnings above); photo2nerf needs at "
             "least {} (ingest.min_images): add more photos of the scene, taken from different places",
             count, report.input_folder, report.skipped.size(),
             duplicates ? format(", {} of them copies of another photo", duplicates) : "", min_images));
}

std::vector<std::variant<IngestedImage, SkippedPhoto>> IngestPhotos(const std::vector<fs::path>& photos,
                                                                    const std::vector<fs::path>& masks,
                                                                    const IngestResult& out,
                                                                    const IngestOptions& options) {
  std::vector<std::variant<IngestedImage, SkippedPhoto>> results(photos.size());
  if (photos.empty()) return results;
  if (!masks.empty()) fs::create_directories(out.masks());
  Progress progress("ingest: decoding", static_cast<int64_t>(photos.size()), "images");
  tbb::parallel_for(size_t{0}, photos.size(), [&](size_t i) {
    if (CancelRequested()) return;
    results[i] = IngestOne(photos[i], masks.empty() ? fs::path() : masks[i], out, options);
    progress.Add();
  });
  ThrowIfCancelled();
  return results;
}

// Adds the decoded images to the report, skipping copies of an earlier one; UserError when two map to one name.
void AddImages(const std::vector<std::variant<IngestedImage, SkippedPhoto>>& results, const fs::path& input,
               const IngestResult& out, IngestReport* report) {
  std::set<std::string> names;
  std::map<std::string, std::string> first_with_fingerprint;
  std::set<std::pair<int, int>> sizes;
  for (const auto& result : results) {
    if (const SkippedPhoto* skip = std::get_if<SkippedPhoto>(&result)) {
      LogWarning(format("ingest: skipped {}: {}", skip->file, skip->reason));
      report->skipped.push_back(*skip);
      continue;
    }
    const IngestedImage& image = std::get<IngestedImage>(result);
    if (!names.insert(image.name).second) {
      throw UserError(
          format("two photos in '{}' map to the image name {}; rename one of them", input.string(), image.name));
    }
    // A copy adds nothing to the reconstruction, and one copy held out while another is trained on would make
    // the held-out error a lie: only the first (by name; a video's frames after the photos) is kept.
    const std::string file = image.frame ? image.name : image.source;
    const auto [it, first] = first_with_fingerprint.emplace(image.fingerprint, file);
    if (!first) {
      fs::remove(out.images() / image.name);
      fs::remove(out.masks() / image.name);
      const std::string reason = kDuplicateReason + it->second;
      LogWarning(format("ingest: skipped {}: {}", file, reason));
      report->skipped.push_back({file, reason});
      continue;
    }
    sizes.insert({image.width, image.height});
    report->images.push_back(image);
  }
  if (sizes.size() > 1) {
    LogWarning(format("ingest: the images have {} different sizes; sfm will give each size a camera of its own",
                      sizes.size()));
  }
}

}  // namespace

void IngestOptions::Check() const {
  CheckField(*this, max_image_size, max_image_size == 0 || max_image_size >= 16,
             format("must be 0 (keep the size) or at least 16 pixels, not {}", max_image_size));
  CheckField(*this, min_images, min_images >= 1, format("must be at least 1, not {}", min_images));
  const std::optional<double> frames = video_frames.value;
  CheckField(
      *this, video_frames, !frames || (*frames >= 1 && *frames <= 100000 && *frames == std::floor(*frames)),
      format("must be auto or a whole number of frames from 1 to 100000, not {}", AutoOrNumberText(video_frames)));
}

InputFiles ListInputs(const fs::path& input) {
  std::error_code error;
  const fs::file_status status = fs::status(input, error);
  if (!fs::exists(status)) {
    throw UserError(format("photo folder '{}' does not exist; give the folder that holds your photos", input.string()));
  }
  InputFiles files;
  if (!fs::is_directory(status)) {
    if (IsVideoFile(input)) {
      files.videos.push_back(input);
      return files;
    }
    throw UserError(
        format("'{}' is a file, not a folder or a video; give the folder that holds your photos", input.string()));
  }
  size_t other_files = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(input, error)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.' || !entry.is_regular_file()) continue;
    if (kImageExtensions.count(LowerExtension(entry.path()))) {
      files.photos.push_back(entry.path());
    } else if (IsVideoFile(entry.path())) {
      files.videos.push_back(entry.path());
    } else {
      ++other_files;
    }
  }
  if (error) throw UserError(format("cannot list the photo folder '{}': {}", input.string(), error.message()));
  if (files.photos.empty() && files.videos.empty()) {
    throw UserError(
        format("no photos or videos in '{}' (looked for .jpg, .jpeg, .png, .tif, .tiff, .exr, .mp4, "
               ".mov, .m4v, .avi, .mkv, .webm{})",
               input.string(), other_files ? format("; {} other files were ignored", other_files) : ""));
  }
  std::sort(files.photos.begin(), files.photos.end());
  std::sort(files.videos.begin(), files.videos.end());
  return files;
}

std::map<std::string, std::string> IngestStage::ExternalInputs(const Workspace& workspace, const Config&) const {
  const fs::path input = InputFolder(workspace);
  InputFiles files;
  try {
    files = ListInputs(input);
  } catch (const UserError&) {
    return {{"folder " + input.string(), "unreadable or without photos"}};  // Run() says why
  }
  std::vector<fs::path> masks;
  try {
    masks = PhotoMasks(input, files);
  } catch (const UserError&) {
    return {{"folder " + MasksFolder(input).string(), "unusable"}};  // Run() says why
  }
  std::map<std::string, std::string> inputs;
  for (const auto& [kind, paths] :
       {std::pair{"image ", &files.photos}, std::pair{"video ", &files.videos}, std::pair{"mask ", &masks}}) {
    const std::vector<std::string> digests = Sha1OfFiles(*paths);
    for (size_t i = 0; i < paths->size(); ++i) inputs[kind + (*paths)[i].filename().string()] = digests[i];
  }
  return inputs;
}

void IngestStage::CheckResult(const fs::path& result_dir, const Config& config) const {
  const IngestOptions options = ReadOptions<IngestOptions>(config);
  CheckImageCount(IngestReport::Read(IngestResult{result_dir}.report()), options.min_images);
}

void IngestStage::Run(StageContext& context) const {
  const IngestOptions options = ReadOptions<IngestOptions>(context.config);
  const fs::path input = InputFolder(context.workspace);
  const InputFiles files = ListInputs(input);
  const IngestResult out{context.output_dir};
  fs::create_directories(out.images());

  const std::vector<fs::path> masks = PhotoMasks(input, files);
  std::vector<std::variant<IngestedImage, SkippedPhoto>> results = IngestPhotos(files.photos, masks, out, options);
  IngestReport report;
  report.input_folder = input.string();
  for (const fs::path& file : files.videos) {
    const std::optional<double> count = options.video_frames.value;
    VideoIngest video =
        IngestVideo(file, out.images(), count ? std::optional<int>(*count) : std::nullopt, options.max_image_size);
    LogInfo(
        format("ingest: {}: {} frames in {:.1f} s; took {}, left {} nearly repeating the frame before and the "
               "rest for a sharper frame near them",
               video.video.file, video.video.frames, video.video.seconds, video.video.taken.size(),
               video.video.repeats.size()));
    results.insert(results.end(), video.images.begin(), video.images.end());
    report.videos.push_back(std::move(video.video));
    ThrowIfCancelled();
  }
  AddImages(results, input, out, &report);
  WriteJsonAtomic(out.report(), report.ToJson());
  CheckImageCount(report, options.min_images);
  context.summary = {{"images", report.images.size()}, {"skipped", report.skipped.size()}};
  LogInfo(format("ingest: {} images, {} skipped{}", report.images.size(), report.skipped.size(),
                 masks.empty() ? "" : format("; each photo's mask from '{}'", MasksFolder(input).string())));
}

}  // namespace p2n
