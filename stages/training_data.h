#pragma once
// The photos and cameras a field trains and is scored on, read from the poses stage's transforms.json: what the
// train, render and report stages (and the benchmarks) share.

#include <array>
#include <filesystem>
#include <string>

#include "nerf/trainer.h"
#include "stages/dataset_import.h"

namespace p2n {

// The view's image decoded to 8-bit RGB or RGBA (grey expanded); UserError naming the file when it cannot be read or
// its size is not the camera's.
TrainView LoadTrainView(const ImportedView& imported);
// The split held out for evaluation: "test" when any view has it, else "val".
std::string HeldoutSplit(const ImportedDataset& dataset);

// The training views ("train" split) and held-out views (the "test" split when it has images, else "val") of a
// transforms.json whose images lie inside `root`, decoded to 8 bits; UserError naming a bad file.
TrainingData LoadTrainingData(const std::filesystem::path& transforms, const std::filesystem::path& root,
                              std::string* heldout_split);
// The colour transparent images were composited on, as transforms.json records it (white when it does not).
std::array<float, 3> DatasetBackground(const std::filesystem::path& transforms);
// The kind of dataset the poses came from as transforms.json records it ("blender", "llff", ...; "" for photos).
std::string SourceDatasetKind(const std::filesystem::path& transforms);

}  // namespace p2n
