#pragma once
// The stages of photo2nerf in order, and every option they and the runner read.

#include <filesystem>
#include <memory>
#include <optional>

#include "pipeline/options.h"
#include "pipeline/run_options.h"
#include "pipeline/runner.h"

namespace p2n {

OptionRegistry AllOptions();
// Checks every section's values (XxxOptions::Check()); UserError naming the first bad option.
void CheckAllOptions(const Config& config);
// The stages for `input`: ingest -> sfm -> poses for a folder of photos; one import stage (named poses) for a
// dataset that already has cameras (see dataset_import.h). No input: the photo stages.
Runner MakeRunner(const std::optional<std::filesystem::path>& input = std::nullopt);

}  // namespace p2n
