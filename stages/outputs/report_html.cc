#include "stages/outputs/report_html.h"

#include <OpenImageIO/strutil.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <fstream>
#include <sstream>

namespace p2n {
namespace {

constexpr const char* kStyle = R"(
body { font-family: sans-serif; margin: 2em auto; max-width: 1280px; color: #222; padding: 0 1em; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.6em; }
.muted { color: #777; } .cards { display: flex; flex-wrap: wrap; gap: 1em; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 0.6em 1em; min-width: 9em; }
.card .value { font-size: 1.6em; font-weight: bold; } .card .label { color: #666; font-size: 0.9em; }
.warnings { border: 2px solid #c62828; background: #fdecea; border-radius: 6px; padding: 0.2em 1em; margin: 1em 0; }
.warnings h2 { color: #c62828; margin-top: 0.6em; }
table { border-collapse: collapse; } td, th { border: 1px solid #ddd; padding: 0.3em 0.6em; text-align: left;
  vertical-align: top; font-size: 0.92em; } th { background: #f4f4f4; }
.triple { display: flex; gap: 0.5em; align-items: flex-start; margin-bottom: 1em; }
.triple figure { margin: 0; flex: 1; } .triple img { max-width: 100%; display: block; }
figcaption { font-size: 0.85em; color: #555; } canvas { border: 1px solid #ddd; cursor: grab; }
.plots { display: flex; flex-wrap: wrap; gap: 1em; } code { font-size: 0.9em; }
)";

// Turns with the mouse; data: {cameras: [{c, r (3x3 row-major, world_from_cam), w, h, fx, fy, heldout}],
// points: [x, y, z, ...], colours: [r, g, b, ...], extent}.
constexpr const char* kViewerScript = R"(
(function () {
  const data = JSON.parse(document.getElementById('scene-data').textContent);
  const canvas = document.getElementById('scene-view');
  const ctx = canvas.getContext('2d');
  let yaw = 0.7, pitch = 0.45, zoom = 1, drag = null;
  function project(p) {
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    const x = cy * p[0] + sy * p[1], y = -sy * p[0] + cy * p[1];
    const up = -sp * y + cp * p[2], depth = cp * y + sp * p[2];
    const s = zoom * canvas.height / (2.2 * data.extent);
    return [canvas.width / 2 + s * x, canvas.height / 2 - s * up, depth];
  }
  function draw() {
    ctx.fillStyle = '#fff';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    const n = data.points.length / 3;
    for (let i = 0; i < n; ++i) {
      const q = project([data.points[3 * i], data.points[3 * i + 1], data.points[3 * i + 2]]);
      ctx.fillStyle = 'rgb(' + data.colours[3 * i] + ',' + data.colours[3 * i + 1] + ',' + data.colours[3 * i + 2] + ')';
      ctx.fillRect(q[0] - 1, q[1] - 1, 2, 2);
    }
    const size = 0.08 * data.extent;
    for (const cam of data.cameras) {
      const corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(function (k) {
        const v = [k[0] * cam.w / (2 * cam.fx), k[1] * cam.h / (2 * cam.fy), -1];
        const p = [0, 1, 2].map(function (r) {
          return cam.c[r] + size * (cam.r[3 * r] * v[0] + cam.r[3 * r + 1] * v[1] + cam.r[3 * r + 2] * v[2]);
        });
        return project(p);
      });
      const c = project(cam.c);
      ctx.strokeStyle = cam.heldout ? '#e07000' : '#1f5fbf';
      ctx.beginPath();
      for (const q of corners) { ctx.moveTo(c[0], c[1]); ctx.lineTo(q[0], q[1]); }
      ctx.moveTo(corners[3][0], corners[3][1]);
      for (const q of corners) ctx.lineTo(q[0], q[1]);
      ctx.stroke();
    }
    canvas.dataset.drawn = data.cameras.length + ' cameras, ' + n + ' points';
  }
  canvas.addEventListener('mousedown', function (e) { drag = [e.clientX, e.clientY]; });
  window.addEventListener('mouseup', function () { drag = null; });
  window.addEventListener('mousemove', function (e) {
    if (!drag) return;
    yaw += 0.01 * (e.clientX - drag[0]);
    pitch = Math.max(-1.5, Math.min(1.5, pitch + 0.01 * (e.clientY - drag[1])));
    drag = [e.clientX, e.clientY];
    draw();
  });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    zoom *= Math.exp(-0.001 * e.deltaY);
    draw();
  }, {passive: false});
  draw();
})();
)";

std::string ReadBytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return in ? bytes.str() : std::string();
}

}  // namespace

std::string HtmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string ImageDataUri(const std::filesystem::path& image, int max_width, const std::array<float, 3>& background) {
  cv::Mat pixels = cv::imread(image.string(), cv::IMREAD_UNCHANGED);
  if (pixels.empty()) return "";
  if (pixels.depth() != CV_8U) pixels.convertTo(pixels, CV_8U, pixels.depth() == CV_16U ? 1.0 / 257 : 255.0);
  if (pixels.channels() == 1) cv::cvtColor(pixels, pixels, cv::COLOR_GRAY2BGR);
  if (pixels.channels() == 4) {  // composited on the background, as the renders are
    cv::Mat composited(pixels.size(), CV_8UC3);
    pixels.forEach<cv::Vec4b>([&](const cv::Vec4b& bgra, const int* at) {
      const float alpha = bgra[3] / 255.0f;
      for (int c = 0; c < 3; ++c) {
        composited.at<cv::Vec3b>(at[0], at[1])[c] =
            cv::saturate_cast<uint8_t>(alpha * bgra[c] + (1 - alpha) * 255 * background[2 - c]);
      }
    });
    pixels = composited;
  }
  if (pixels.cols > max_width) {
    cv::resize(pixels, pixels, cv::Size(max_width, std::max(1, pixels.rows * max_width / pixels.cols)), 0, 0,
               cv::INTER_AREA);
  }
  std::vector<uint8_t> jpeg;
  if (!cv::imencode(".jpg", pixels, jpeg, {cv::IMWRITE_JPEG_QUALITY, 90})) return "";
  return "data:image/jpeg;base64," + OIIO::Strutil::base64_encode(std::string(jpeg.begin(), jpeg.end()));
}

std::string FileDataUri(const std::filesystem::path& file, const std::string& mime) {
  const std::string bytes = ReadBytes(file);
  return bytes.empty() ? "" : "data:" + mime + ";base64," + OIIO::Strutil::base64_encode(bytes);
}

std::string SceneViewerHtml(const std::vector<ViewerCamera>& cameras, const std::vector<ColouredPoint>& points,
                            size_t max_points) {
  nlohmann::json data = {
      {"cameras", nlohmann::json::array()}, {"points", nlohmann::json::array()}, {"colours", nlohmann::json::array()}};
  double extent = 1;
  for (const ViewerCamera& view : cameras) {
    const Eigen::Matrix4d& pose = view.camera.world_from_cam;
    nlohmann::json rotation = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation.push_back(pose(r, c));
    }
    data["cameras"].push_back({{"c", {pose(0, 3), pose(1, 3), pose(2, 3)}},
                               {"r", rotation},
                               {"w", view.camera.width},
                               {"h", view.camera.height},
                               {"fx", view.camera.fx},
                               {"fy", view.camera.fy},
                               {"heldout", view.heldout}});
    extent = std::max(extent, pose.block<3, 1>(0, 3).norm());
  }
  const size_t stride = std::max<size_t>(1, (points.size() + max_points - 1) / max_points);
  for (size_t i = 0; i < points.size(); i += stride) {
    if (!points[i].position.allFinite() || points[i].position.norm() > 3 * extent) continue;
    for (int k = 0; k < 3; ++k) {
      data["points"].push_back(std::round(points[i].position[k] * 1e4) / 1e4);
      data["colours"].push_back(points[i].rgb[k]);
    }
  }
  data["extent"] = extent;
  std::string json = data.dump();
  // Inside <script>, "</" would end the element early.
  for (size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at)) json.replace(at, 2, "<\\/");
  return "<canvas id=\"scene-view\" width=\"900\" height=\"560\"></canvas>\n"
         "<p class=\"muted\">Drag to turn, wheel to zoom. Blue: training cameras; orange: held-out cameras.</p>\n"
         "<script type=\"application/json\" id=\"scene-data\">" +
         json + "</script>\n<script>" + kViewerScript + "</script>\n";
}

std::string HtmlPage(const std::string& title, const std::string& body) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + HtmlEscape(title) +
         "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n" + body + "</body>\n</html>\n";
}

}  // namespace p2n
