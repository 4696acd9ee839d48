#include "formats/image_masks.h"

#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <map>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

const std::set<std::string> kMaskExtensions = {"png", "jpg", "jpeg", "tif", "tiff", "bmp", "webp"};

// The masks in the folder by their name without its last extension (IMG_1.JPG.png -> IMG_1.JPG).
std::map<std::string, std::vector<fs::path>> MasksByStem(const fs::path& masks) {
  std::map<std::string, std::vector<fs::path>> by_stem;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(masks, error)) {
    if (entry.is_regular_file() && kMaskExtensions.count(LowerExtension(entry.path())))
      by_stem[entry.path().stem().string()].push_back(entry.path());
  }
  if (error) throw UserError(format("cannot list the masks in '{}': {}", masks.string(), error.message()));
  return by_stem;
}

}  // namespace

fs::path MasksFolder(const fs::path& input) {
  const fs::path folder = input.has_filename() ? input : input.parent_path();
  if (fs::is_directory(folder / "masks")) return folder / "masks";
  const fs::path beside = folder.parent_path() / "masks";
  return folder.filename() == "images" && fs::is_directory(beside) ? beside : fs::path();
}

std::vector<fs::path> MatchMasks(const fs::path& masks, const std::vector<fs::path>& photos) {
  const std::map<std::string, std::vector<fs::path>> by_stem = MasksByStem(masks);
  std::vector<fs::path> matched;
  std::vector<std::string> missing;
  for (const fs::path& photo : photos) {
    const std::string stem = photo.stem().string();
    fs::path mask;
    for (const std::string& key : {photo.filename().string(), stem, stem + "_mask"}) {
      const auto it = by_stem.find(key);
      if (it == by_stem.end()) continue;
      if (it->second.size() > 1) {
        throw UserError(format("'{}' has two masks for '{}' ('{}' and '{}'): keep one", masks.string(),
                               photo.filename().string(), it->second[0].filename().string(),
                               it->second[1].filename().string()));
      }
      mask = it->second.front();
      break;
    }
    if (mask.empty()) missing.push_back(photo.filename().string());
    matched.push_back(mask);
  }
  if (!missing.empty()) {
    const std::string first = missing.front(), stem = fs::path(first).stem().string();
    throw UserError(
        format("'{}' has no mask for {} of the {} photos (the first: '{}'): name each photo's mask as the "
               "photo ({}.png, {}.png or {}_mask.png), or run with --poses.masks false to use none",
               masks.string(), missing.size(), photos.size(), first, stem, first, stem));
  }
  return matched;
}

OIIO::ImageBuf ReadMask(const fs::path& mask, const fs::path& photo, int width, int height, int orientation) {
  ReadImageResult read = ReadImage(mask);
  if (!read.ok()) throw UserError(format("cannot use the mask '{}': {}", mask.string(), read.error));
  OIIO::ImageBuf alpha = OIIO::ImageBufAlgo::channels(read.image, 1, {0});
  if (orientation >= 5 && orientation <= 8 && width != height && alpha.spec().width == height &&
      alpha.spec().height == width) {
    alpha.specmod().attribute("Orientation", orientation);
    alpha = OIIO::ImageBufAlgo::reorient(alpha);
  }
  const int64_t mask_w = alpha.spec().width, mask_h = alpha.spec().height;
  if (mask_w != width || mask_h != height) {
    // The same shape: the products of each side with the other's differ by less than a row of pixels.
    if (std::abs(mask_w * height - width * mask_h) > std::max<int64_t>(mask_w, width)) {
      throw UserError(format("the mask '{}' is {}x{} but its photo '{}' is {}x{}: give the mask the photo's size",
                             mask.string(), mask_w, mask_h, photo.string(), width, height));
    }
    alpha = OIIO::ImageBufAlgo::resize(alpha, "", 0, OIIO::ROI(0, width, 0, height, 0, 1, 0, 1));
  }
  OIIO::ImageBuf out = OIIO::ImageBufAlgo::copy(alpha, OIIO::TypeDesc::FLOAT);
  for (OIIO::ImageBuf::Iterator<float> p(out); !p.done(); ++p) {
    const float a = std::clamp(static_cast<float>(p[0]), 0.0f, 1.0f);
    p[0] = a < 8.0f / 255 ? 0.0f : a > 247.0f / 255 ? 1.0f : a;
  }
  return out;
}

OIIO::ImageBuf WithMask(const OIIO::ImageBuf& image, const fs::path& photo, const fs::path& mask) {
  namespace algo = OIIO::ImageBufAlgo;
  const OIIO::ImageSpec& spec = image.spec();
  OIIO::ImageBuf alpha = ReadMask(mask, photo, spec.width, spec.height);
  const bool has_alpha = spec.nchannels == 2 || spec.nchannels == 4;
  const int colours = has_alpha ? spec.nchannels - 1 : spec.nchannels;
  if (has_alpha) alpha = algo::mul(alpha, algo::channels(image, 1, {colours}));
  OIIO::ImageBuf out(OIIO::ImageSpec(spec.width, spec.height, colours + 1, spec.format));
  if (!algo::channel_append(out, algo::channels(image, colours, {}), alpha))
    throw UserError(format("cannot give '{}' its mask '{}': {}", photo.string(), mask.string(), out.geterror()));
  return out;
}

}  // namespace p2n
