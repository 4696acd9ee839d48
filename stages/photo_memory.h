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

// What a window over `subset` (views `indices` of a set of training photos, whose view v `read` reads) reads view i
// with: the set's decoded copy `photos` where there is one, else a copy of the subset's own decoded into `folder`
// (kept in `own`: a block's job reads no photo but its block's).
PhotoWindow::Loader SubsetReader(const std::vector<TrainView>& subset, const std::vector<size_t>& indices,
                                 const std::shared_ptr<const DecodedPhotos>& photos, const PhotoWindow::Loader& read,
                                 const std::filesystem::path& folder, const std::string& label,
                                 std::shared_ptr<const DecodedPhotos>* own);

}  // namespace p2n
