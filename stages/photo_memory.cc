#include "stages/photo_memory.h"

#include <tbb/parallel_for.h>

#include <numeric>
#include <stdexcept>

#include "base/errors.h"
#include "base/format.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/training_data.h"

namespace p2n {

namespace fs = std::filesystem;

double MegabytesToBytes(double megabytes) { return megabytes * (1 << 20); }

std::shared_ptr<const DecodedPhotos> DecodePhotos(const fs::path& folder, const std::vector<size_t>& sizes,
                                                  const PhotoWindow::Loader& decode, const std::string& label) {
  fs::create_directories(folder);
  Progress progress(label, static_cast<int64_t>(sizes.size()), "images");
  return std::make_shared<const DecodedPhotos>(folder, sizes, [&](size_t v) {
    std::vector<uint8_t> pixels = decode(v);
    progress.Add();
    return pixels;
  });
}

WindowedPhotos DecodeForWindow(const std::vector<TrainView>& views, double megabytes, const std::string& option,
                               const std::string& stage, const fs::path& folder, const PhotoWindow::Loader& decode) {
  WindowedPhotos out;
  try {
    out.window = PhotoWindow::WindowSize(views, MegabytesToBytes(megabytes));
  } catch (const std::invalid_argument& e) {
    throw UserError(format("{} is {} MB: {}; raise it", option, megabytes, e.what()));
  }
  std::vector<size_t> sizes;
  for (const TrainView& view : views) sizes.push_back(view.PixelBytes());
  const double bytes = std::accumulate(sizes.begin(), sizes.end(), 0.0);
  LogInfo(
      format("{}: the {} training photos would take {:.1f} MB, more than {} ({} MB): {} at a time in memory, "
             "read from their decoded copy in {}",
             stage, views.size(), bytes / MegabytesToBytes(1), option, megabytes, out.window, folder.string()));
  out.photos = DecodePhotos(folder, sizes, decode, stage + ": decoding the photos");
  return out;
}

void LoadHeldoutPhotos(const ImportedDataset& poses, double megabytes, const std::string& option,
                       const std::string& stage, const fs::path& folder, TrainingData* data) {
  double training = 0;
  for (const TrainView& view : data->train) training += view.PixelBytes();
  const double memory = MegabytesToBytes(megabytes), room = training <= memory ? memory - training : 0;
  const std::vector<const ImportedView*> views = HeldoutViews(poses);
  const auto decode = [views](size_t v) { return LoadTrainView(*views[v]).pixels; };
  std::vector<size_t> sizes;
  for (const TrainView& view : data->heldout) sizes.push_back(view.PixelBytes());
  const double bytes = std::accumulate(sizes.begin(), sizes.end(), 0.0);
  if (bytes <= room) {
    Progress progress(stage + ": loading the held-out images", static_cast<int64_t>(views.size()), "images");
    tbb::parallel_for(size_t{0}, views.size(), [&](size_t v) {
      data->heldout[v].pixels = decode(v);
      progress.Add();
    });
    return;
  }
  LogInfo(
      format("{}: the {} held-out photos ({:.1f} MB) do not fit in what the training photos leave of {}: each "
             "evaluation reads them from their decoded copy in {}",
             stage, views.size(), bytes / MegabytesToBytes(1), option, folder.string()));
  const std::shared_ptr<const DecodedPhotos> photos =
      DecodePhotos(folder, sizes, decode, stage + ": decoding the held-out photos");
  data->read_heldout = [photos](size_t v) { return photos->Read(v); };
}

BorrowedViews::~BorrowedViews() {
  for (const auto& [from, to] : lent) (*lender)[from].pixels = std::move((*views)[to].pixels);
}

namespace {

// What a window over `subset` (views `indices` of a set whose view v `source.read` reads) reads view i with: the
// set's decoded copy where there is one, else a copy of the subset's own (kept in `own`).
PhotoWindow::Loader SubsetReader(const std::vector<TrainView>& subset, const std::vector<size_t>& indices,
                                 const PhotoSource& source, std::shared_ptr<const DecodedPhotos>* own) {
  if (source.photos) return [photos = source.photos, indices](size_t v) { return photos->Read(indices[v]); };
  std::vector<size_t> sizes;
  for (const TrainView& view : subset) sizes.push_back(view.PixelBytes());
  *own = DecodePhotos(
      source.folder, sizes, [&](size_t v) { return source.read(indices[v]); }, source.label);
  return [copy = *own](size_t v) { return copy->Read(v); };
}

}  // namespace

void BorrowViews(std::vector<TrainView>* lender, const std::vector<size_t>& indices, const PhotoSource& source,
                 std::vector<TrainView>* views, BorrowedViews* borrowed) {
  borrowed->lender = lender;
  borrowed->views = views;
  views->clear();
  double bytes = 0;
  for (const size_t v : indices) {
    TrainView& from = (*lender)[v];
    bytes += from.PixelBytes();
    TrainView view = WithoutPixels(from);
    if (!from.pixels.empty()) {
      borrowed->lent.emplace_back(v, views->size());
      view.pixels = std::move(from.pixels);
    }
    views->push_back(std::move(view));
  }
  if (bytes > source.memory) {
    const PhotoWindow::Loader read = SubsetReader(*views, indices, source, &borrowed->photos);
    borrowed->window = std::make_unique<PhotoWindow>(views, read, source.memory, source.seed);
    return;
  }
  tbb::parallel_for(size_t{0}, indices.size(), [&](size_t i) {
    if ((*views)[i].pixels.empty()) (*views)[i].pixels = source.read(indices[i]);
  });
}

}  // namespace p2n
