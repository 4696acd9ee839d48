#pragma once
// The photos and cameras a field trains and is scored on, read from the poses stage's transforms.json: what the
// train, render and report stages (and the benchmarks) share.

#include <array>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "formats/dataset_import.h"
#include "nerf/trainer.h"

namespace p2n {

// The view's image decoded to 8-bit RGB or RGBA (grey expanded); UserError naming the file when it cannot be read or
// its size is not the camera's.
TrainView LoadTrainView(const ImportedView& imported);
// The same view without its pixels: the channels they will have from the file's header.
TrainView TrainViewHeader(const ImportedView& imported);
// The split held out for evaluation: test when any view has it, else val.
ViewSplit HeldoutSplit(const ImportedDataset& dataset);

// Whether the photos were taken from one side looking one way: cameras that face forward (FacesForward), whatever
// the dataset's format (LLFF's poses_bounds.npy holds captures taken around an object too). Such a scene trains in
// normalised device coordinates and its video is a spiral.
bool ForwardFacingCapture(const ImportedDataset& dataset);

// The training views ("train" split) and held-out views (HeldoutSplit's) of the poses stage's transforms.json
// (LoadTransformsJson), decoded to 8 bits, with the background its images were composited on; UserError naming
// a bad file. With `depth_points`, each training view's depth points too (from sparse_points.ply and
// sparse_tracks.json beside transforms.json; none when the poses stage has no tracks). With a finite `photo_bytes`,
// the training views' pixels are left out when they would take more than that in all (a PhotoWindow then holds some
// at a time), and the held-out views' always (LoadHeldoutPhotos, stages/photo_memory.h, places them).
TrainingData LoadTrainingData(const ImportedDataset& poses, bool depth_points = false,
                              double photo_bytes = std::numeric_limits<double>::infinity());
// The training views of LoadTrainingData without their pixels (each file's header read: TrainViewHeader), with their
// depth points when `depth_points`, and no held-out view: what a part of the training that reads only some of the
// photos starts from (a field block's job, stages/fitting/train_blocks.h).
TrainingData LoadTrainingCameras(const ImportedDataset& poses, bool depth_points = false);
// The training views ("train" split), in the order LoadTrainingData keeps them.
std::vector<const ImportedView*> TrainingViews(const ImportedDataset& poses);
// The held-out views (HeldoutSplit's), in the order LoadTrainingData keeps them.
std::vector<const ImportedView*> HeldoutViews(const ImportedDataset& poses);

// The names of `views`, in order: what a stage's blocks keep of the training views they index (CheckSameViews).
std::vector<std::string> ViewNames(const std::vector<TrainView>& views);
// UserError when `views` are not those named `names`, in order: a block's job on a machine where a photo of the poses
// stage (its `transforms`) cannot be read, whose frame transforms.json's reader leaves out, would train on other
// views than the block's. `who` begins the message ("train: block 2"). An empty `names` (an older version's) passes.
void CheckSameViews(const std::vector<std::string>& names, const std::vector<TrainView>& views, const std::string& who,
                    const std::filesystem::path& transforms);

}  // namespace p2n
