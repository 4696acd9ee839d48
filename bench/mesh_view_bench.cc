// How the export's textured mesh looks in a viewer: draws WS/50_export/mesh.glb with three.js (GLTFLoader, in
// headless Chromium: viewer/test/mesh_check.mjs) from every held-out camera and compares each frame with the photo
// (both composited on the dataset's background): PSNR and SSIM per view, PSNR where the mesh covers the frame and
// the share it covers, their means, and the file's size and triangles. The frames (RGBA, transparent where no mesh
// is) are written to OUT_DIR (0.png, 1.png, ... in the held-out views' order).
// Usage: mesh_view_bench WORKSPACE OUT_DIR

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "base/file_util.h"
#include "base/image_io.h"
#include "formats/output_frame.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"

namespace fs = std::filesystem;
using namespace p2n;

namespace {

FloatImage LoadRgba(const fs::path& path) {
  const ReadImageResult read = ReadImage(path);
  if (!read.ok()) throw std::runtime_error(read.error);
  FloatImage image{read.image.spec().width, read.image.spec().height, 4, {}};
  image.pixels.resize(size_t(4) * image.width * image.height);
  read.image.get_pixels(OIIO::ROI(0, image.width, 0, image.height, 0, 1, 0, 4), OIIO::TypeDesc::FLOAT,
                        image.pixels.data());
  return image;
}

// The frame over `background` (RGB), and the mean squared error against `photo` where it is opaque, with the share
// of such pixels.
struct Composited {
  FloatImage rgb;
  double covered_mse = 0, covered = 0;
};
Composited Composite(const FloatImage& rgba, const std::array<float, 3>& background, const FloatImage& photo) {
  Composited out{{rgba.width, rgba.height, 3, std::vector<float>(size_t(3) * rgba.width * rgba.height)}};
  size_t opaque = 0;
  for (size_t i = 0; i < size_t(rgba.width) * rgba.height; ++i) {
    const float alpha = rgba.pixels[4 * i + 3];
    for (int c = 0; c < 3; ++c) out.rgb.pixels[3 * i + c] = rgba.pixels[4 * i + c] + (1 - alpha) * background[c];
    if (alpha < 0.999f) continue;
    ++opaque;
    for (int c = 0; c < 3; ++c) out.covered_mse += std::pow(out.rgb.pixels[3 * i + c] - photo.pixels[3 * i + c], 2) / 3;
  }
  out.covered_mse /= std::max<size_t>(1, opaque);
  out.covered = double(opaque) / (size_t(rgba.width) * rgba.height);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: mesh_view_bench WORKSPACE OUT_DIR\n");
    return 2;
  }
  const fs::path workspace = argv[1], out_dir = argv[2];
  fs::create_directories(out_dir);
  const ImportedDataset poses = LoadTransformsJson(workspace / "20_poses" / "transforms.json", workspace);
  const TrainingData data = LoadTrainingData(poses);
  const ExportReport exported = ExportReport::Read(workspace / "50_export" / "export_report.json");
  const OutputFrame upright = UprightFrame(MakeOutputFrame(exported.frame, poses));
  nlohmann::json cameras = nlohmann::json::array();
  for (const TrainView& view : data.heldout) {
    const PinholeCamera& c = view.camera;
    const Eigen::Matrix4d pose = upright.Pose(c.world_from_cam);
    cameras.push_back({{"width", c.width},
                       {"height", c.height},
                       {"fx", c.fx},
                       {"fy", c.fy},
                       {"cx", c.cx},
                       {"cy", c.cy},
                       {"pose", std::vector<double>(pose.data(), pose.data() + 16)}});
  }
  const double scale = upright.Scale();
  WriteJsonAtomic(out_dir / "cameras.json", {{"near", 0.01 * scale}, {"far", 100 * scale}, {"cameras", cameras}});
  const fs::path glb = workspace / "50_export" / "mesh.glb";
  const std::string command = std::string(P2N_NODE) + " " + P2N_NODE_DIR + "/mesh_check.mjs '" + glb.string() + "' '" +
                              (out_dir / "cameras.json").string() + "' '" + out_dir.string() + "'";
  if (std::system(command.c_str()) != 0) return 1;
  std::vector<double> psnr, ssim, covered_psnr, covered;
  for (size_t v = 0; v < data.heldout.size(); ++v) {
    const FloatImage photo = PhotoOnBackground(data.heldout[v], data.background);
    const Composited drawn = Composite(LoadRgba(out_dir / (std::to_string(v) + ".png")), data.background, photo);
    psnr.push_back(Psnr(drawn.rgb, photo));
    ssim.push_back(Ssim(drawn.rgb, photo));
    covered_psnr.push_back(PsnrOfMse(drawn.covered_mse));
    covered.push_back(drawn.covered);
    std::printf("%s: PSNR %.2f dB, SSIM %.3f; where the mesh is (%.0f%% of the frame): PSNR %.2f dB\n",
                data.heldout[v].name.c_str(), psnr.back(), ssim.back(), 100 * covered.back(), covered_psnr.back());
  }
  std::printf(
      "mesh.glb %.2f MB, %zu triangles (of %zu marched), texture %d; %zu held-out views: PSNR %.2f dB, "
      "SSIM %.3f; where the mesh is (%.0f%% of the frame) PSNR %.2f dB (means)\n",
      fs::file_size(glb) / 1e6, exported.mesh.triangles, exported.mesh.marched_triangles,
      exported.textured.texture_size, psnr.size(), Mean(psnr), Mean(ssim), 100 * Mean(covered), Mean(covered_psnr));
  return 0;
}
