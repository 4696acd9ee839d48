#pragma once
// The splat stage's viewer.html: the splats and the capture's cameras in one self-contained page
// (viewer/viewer_page.h).

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>

#include "formats/output_frame.h"
#include "nerf/trainer.h"
#include "splat/gaussians.h"

namespace p2n {

// Writes the page for `gaussians` and the cameras of `data` (both already in `frame`) atomically; gives its size
// in bytes. `near` is the splats' near plane.
size_t WriteSplatViewer(const std::filesystem::path& path, const std::string& title, const Gaussians<float>& gaussians,
                        const TrainingData& data, const OutputFrame& frame, const std::array<float, 3>& background,
                        double near);

}  // namespace p2n
