#pragma once
// Reading and writing a stage's binary results with errors a user can act on: the engine (nerf/) throws
// std::runtime_error naming the file; a stage turns it into a UserError that says what to do.

#include <filesystem>
#include <functional>

#include "nerf/nerf_model.h"

namespace p2n {

// Runs `write`; a std::runtime_error from it (a full disk, a file-size limit, a read-only folder) becomes a
// UserError that adds what to check. UserErrors pass unchanged.
void WriteOrExplain(const std::function<void()>& write);

// LoadModel, with a damaged or foreign file reported as a UserError that says how to remake it.
NerfModel LoadTrainedModel(const std::filesystem::path& model_bin);

}  // namespace p2n
