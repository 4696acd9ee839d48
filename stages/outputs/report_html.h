#pragma once
// Pieces of the self-contained HTML report: escaping, images and files embedded as data URIs, and a 3D view of
// cameras and points that turns with the mouse (a canvas and a few lines of script: no network needed).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "base/camera.h"
#include "formats/ply.h"

namespace p2n {

std::string HtmlEscape(const std::string& text);

// The image as a JPEG data URI, downsized to at most `max_width` pixels wide, transparency composited on
// `background` (RGB in [0, 1]); empty when it cannot be read.
std::string ImageDataUri(const std::filesystem::path& image, int max_width,
                         const std::array<float, 3>& background = {1, 1, 1});
// Any file as a data URI of that MIME type; empty when it cannot be read.
std::string FileDataUri(const std::filesystem::path& file, const std::string& mime);

struct ViewerCamera {
  PinholeCamera camera;
  bool heldout = false;
};
// A <canvas> with its script: camera frusta (training blue, held-out orange) and coloured points, orthographic,
// dragged to turn and wheeled to zoom. At most `max_points` points are drawn (an even subsample).
std::string SceneViewerHtml(const std::vector<ViewerCamera>& cameras, const std::vector<ColouredPoint>& points,
                            size_t max_points = 20000);

// The page around `body`: title, inline style.
std::string HtmlPage(const std::string& title, const std::string& body);

}  // namespace p2n
