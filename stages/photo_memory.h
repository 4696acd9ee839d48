#pragma once
// Training photos too many for memory (more than a stage's photo_memory, in MB): a window over them
// (base/photo_window.h) reading from their decoded copy (base/decoded_photos.h). What the train and splat stages and
// their blocks share.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "base/decoded_photos.h"
#include "base/photo_window.h"
#include "formats/dataset_import.h"

namespace p2n {

// A photo_memory setting (MB) in bytes.
double MegabytesToBytes(double megabytes);

// Training photos beyond a stage's photo_memory: the size of a window over them, and their decoded copy.
struct WindowedPhotos {
  size_t window = 0;
  std::shared_ptr<const DecodedPhotos> photos;
};
// For `views` (without their pixels), which take more than `megabytes` (the option `option` of stage `stage`): the
// window's size (PhotoWindow::WindowSize; a UserError naming the option when it holds too few), said in the log, and
// their copy decoded by `decode` into `folder`.
WindowedPhotos DecodeForWindow(const std::vector<TrainView>& views, double megabytes, const std::string& option,
                               const std::string& stage, const std::filesystem::path& folder,
                               const PhotoWindow::Loader& decode);

// The held-out views' pixels (`data`'s, LoadTrainingData's views of `poses` without them): in memory when they fit
// in what `data`'s training views (at the size they are trained at) leave of `megabytes` (the stage's photo_memory,
// its key `option`; nothing when they take more, a window over them holding that much), else decoded into a nameless
// copy in `folder` that each evaluation reads a view at a time (TrainingData::read_heldout), which the log says.
// Only their pixels are set: the cameras are kept.
void LoadHeldoutPhotos(const ImportedDataset& poses, double megabytes, const std::string& option,
                       const std::string& stage, const std::filesystem::path& folder, TrainingData* data);

// Photos of `sizes` bytes decoded by `decode` into a file in `folder` (made if missing), with a progress line `label`.
std::shared_ptr<const DecodedPhotos> DecodePhotos(const std::filesystem::path& folder, const std::vector<size_t>& sizes,
                                                  const PhotoWindow::Loader& decode, const std::string& label);

// Where a block's training views take their pixels from: `read` reads view v of the stage's (from its decoded copy
// `photos` where there is one); a block whose views take more than `memory` bytes trains through a window over them
// (seeded by `seed`), reading from `photos`, or where there is none (a block's job) from a copy of its own decoded
// into `folder` with the progress line `label`.
struct PhotoSource {
  PhotoWindow::Loader read;
  std::shared_ptr<const DecodedPhotos> photos;
  double memory = 0;
  uint64_t seed = 0;
  std::filesystem::path folder;
  std::string label;
};

// The training views a block is optimised on (the field's or the splats'), some of a stage's, in the borrower's
// `views`: their pixels borrowed from the stage's views where those hold them (the whole does not step while a block
// does) and given back when this goes, the others read; or a window over them.
struct BorrowedViews {
  std::vector<TrainView>* views = nullptr;
  std::unique_ptr<PhotoWindow> window;          // over `views`, where they take more than the source's memory
  std::shared_ptr<const DecodedPhotos> photos;  // their own decoded copy, which the window reads (a block's job)
  std::vector<TrainView>* lender = nullptr;
  std::vector<std::pair<size_t, size_t>> lent;  // (the lender's view, this one's)

  BorrowedViews() = default;
  BorrowedViews(const BorrowedViews&) = delete;
  BorrowedViews& operator=(const BorrowedViews&) = delete;
  ~BorrowedViews();
};

// Views `indices` of `lender` into `views` (which must outlive `borrowed`, and stay where it is: the window points
// into it).
void BorrowViews(std::vector<TrainView>* lender, const std::vector<size_t>& indices, const PhotoSource& source,
                 std::vector<TrainView>* views, BorrowedViews* borrowed);

}  // namespace p2n
