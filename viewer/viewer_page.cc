#include "viewer/viewer_page.h"

#include <nlohmann/json.hpp>

#include <string_view>

#include "viewer/viewer_bundle.h"

namespace p2n {
namespace {

// `text` with every "</" made "<\/": a script element's content cannot end it early (JSON and JavaScript read
// both alike).
std::string InScript(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
  }
  return out;
}

// Field by field rather than from nested initialiser lists, whose temporaries clang's AddressSanitizer finds
// read after their scope.
nlohmann::json SceneJson(const SplatViewerScene& scene) {
  nlohmann::json json = nlohmann::json::object(), cameras = nlohmann::json::array();
  for (const SplatViewerCamera& camera : scene.cameras) {
    nlohmann::json c = nlohmann::json::object();
    c["name"] = camera.name;
    c["split"] = camera.split;
    c["width"] = camera.width;
    c["height"] = camera.height;
    c["fx"] = camera.fx;
    c["fy"] = camera.fy;
    c["cx"] = camera.cx;
    c["cy"] = camera.cy;
    c["pose"] = camera.world_from_cam;
    cameras.push_back(std::move(c));
  }
  json["title"] = scene.title;
  json["background"] = scene.background;
  json["cameras"] = std::move(cameras);
  json["centre"] = std::vector<double>{scene.centre.x(), scene.centre.y(), scene.centre.z()};
  json["radius"] = scene.radius;
  json["near"] = scene.near;
  json["far"] = scene.far;
  return json;
}

constexpr const char* kStyle = R"(
html, body { margin: 0; height: 100%; overflow: hidden; font: 13px system-ui, sans-serif; }
canvas { display: block; touch-action: none; }
#p2n-panel { position: fixed; top: 8px; left: 8px; padding: 6px 8px; border-radius: 4px;
             background: rgba(255, 255, 255, 0.85); color: #222; max-width: 90vw; }
#p2n-panel details { margin-top: 4px; }
)";

constexpr const char* kHelp =
    "Drag: orbit. Right-drag or Shift-drag, two fingers: pan. Wheel, pinch: zoom. W A S D: fly, R F: up and "
    "down, Shift: faster. Arrow keys: pan.";

}  // namespace

std::string MeshViewHtml(const std::string& glb, int width, int height) {
  return "<canvas id=\"p2n-mesh-canvas\" style=\"width: " + std::to_string(width) +
         "px; height: " + std::to_string(height) + "px; max-width: 100%; touch-action: none\"></canvas>\n" +
         "<script id=\"p2n-mesh\" type=\"application/octet-stream\">" + Base64(glb.data(), glb.size()) +
         "</script>\n<script>" + InScript(MeshViewerBundle()) + "</script>\n";
}

std::string Base64(const char* data, size_t size) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    const size_t n = std::min<size_t>(3, size - i);
    uint32_t word = 0;
    for (size_t k = 0; k < 3; ++k) word = word << 8 | (k < n ? static_cast<unsigned char>(data[i + k]) : 0);
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kDigits[(word >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

std::string ViewerPage(const SplatViewerScene& scene, const std::vector<char>& splats) {
  std::string page = "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  page += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  // The title comes from the scene's JSON (the script sets it as text): nothing here needs escaping.
  page += std::string("<title>photo2nerf viewer</title>\n<style>") + kStyle + "</style>\n</head>\n<body>\n";
  page +=
      std::string(
          "<canvas id=\"p2n-canvas\"></canvas>\n<div id=\"p2n-panel\"><b id=\"p2n-title\"></b> <label>camera <select "
          "id=\"p2n-camera\"></select></label> <span id=\"p2n-status\">loading"
          "</span><details><summary>controls</summary>") +
      kHelp + "</details></div>\n";
  page += "<script id=\"p2n-scene\" type=\"application/json\">" + InScript(SceneJson(scene).dump()) + "</script>\n";
  page += "<script id=\"p2n-splats\" type=\"application/octet-stream\">" + Base64(splats.data(), splats.size()) +
          "</script>\n";
  page += "<script>" + InScript(ViewerBundle()) + "</script>\n</body>\n</html>\n";
  return page;
}

}  // namespace p2n
