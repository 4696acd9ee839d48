#include "formats/colmap_model.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

struct CameraModelInfo {
  int id;
  const char* name;
  int params;
};

constexpr CameraModelInfo kCameraModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
};

int ModelId(const std::string& name) {
  for (const CameraModelInfo& info : kCameraModels) {
    if (name == info.name) return info.id;
  }
  return -1;
}

constexpr uint64_t kMaxImageSide = 1 << 20;
constexpr size_t kMaxNameLength = 4096;

// Reads little-endian binary records from a file held in memory, refusing to read past its end.
class BinaryReader {
 public:
  explicit BinaryReader(const fs::path& path) : path_(path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(format("cannot read the COLMAP model file '{}'", path.string()));
    std::stringstream buffer;
    buffer << in.rdbuf();
    data_ = buffer.str();
  }
  template <class T>
  T Read(const std::string& what) {
    if (data_.size() - offset_ < sizeof(T)) Fail(what + ": the file ends early (truncated?)");
    T value;
    std::memcpy(&value, data_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  std::string ReadName(const std::string& what) {
    const size_t end = data_.find('\0', offset_);
    if (end == std::string::npos || end - offset_ > kMaxNameLength) Fail(what + ": no terminated name");
    std::string name = data_.substr(offset_, end - offset_);
    offset_ = end + 1;
    return name;
  }
  // A count of records of at least `record_size` bytes each: more than the bytes left is impossible.
  uint64_t ReadCount(const std::string& what, size_t record_size) {
    const uint64_t count = Read<uint64_t>(what);
    if (record_size > 0 && count > (data_.size() - offset_) / record_size) {
      Fail(format("{}: {} records cannot fit in the {} bytes left", what, count, data_.size() - offset_));
    }
    return count;
  }
  void ExpectEnd() {
    if (offset_ != data_.size()) Fail(format("{} unexpected bytes at the end", data_.size() - offset_));
  }
  [[noreturn]] void Fail(const std::string& message) const {
    throw UserError(format("COLMAP model file '{}' is damaged: {}", path_.string(), message));
  }

 private:
  fs::path path_;
  std::string data_;
  size_t offset_ = 0;
};

[[noreturn]] void Invalid(const fs::path& path, const std::string& record, const std::string& problem) {
  throw UserError(format("COLMAP model file '{}': {} {}", path.string(), record, problem));
}

void ValidateCamera(const ColmapCamera& camera, const fs::path& path) {
  const std::string record = format("camera {}", camera.id);
  if (ModelId(camera.model) < 0) Invalid(path, record, format("has an unknown camera model '{}'", camera.model));
  if (static_cast<int>(camera.params.size()) != ColmapModelParamCount(camera.model)) {
    Invalid(path, record,
            format("has {} parameters; {} takes {}", camera.params.size(), camera.model,
                   ColmapModelParamCount(camera.model)));
  }
  if (camera.width == 0 || camera.height == 0 || camera.width > kMaxImageSide || camera.height > kMaxImageSide) {
    Invalid(path, record, format("has an impossible size {}x{}", camera.width, camera.height));
  }
  for (const double p : camera.params) {
    if (!std::isfinite(p)) Invalid(path, record, "has a parameter that is not a finite number");
  }
  if (camera.params[0] <= 0) Invalid(path, record, "has a focal length that is not positive");
}

void ValidateImage(ColmapImage& image, const fs::path& path) {
  const std::string record = format("image {} ({})", image.id, image.name);
  const Eigen::Vector4d q = image.cam_from_world_rotation.coeffs();
  if (!q.allFinite() || !image.cam_from_world_translation.allFinite()) {
    Invalid(path, record, "has a pose that is not finite");
  }
  if (std::abs(q.norm() - 1) > 1e-3) Invalid(path, record, format("has a rotation quaternion of norm {}", q.norm()));
  image.cam_from_world_rotation.normalize();
  if (image.name.empty()) Invalid(path, record, "has no file name");
  for (const Eigen::Vector2d& point : image.points2d) {
    if (!point.allFinite()) Invalid(path, record, "has a 2D point that is not finite");
  }
}

void ValidateModel(ColmapModel& model, const fs::path& folder) {
  for (auto& [id, image] : model.images) {
    if (!model.cameras.count(image.camera_id)) {
      Invalid(folder / "images", format("image {} ({})", id, image.name),
              format("refers to camera {}, which the model does not have", image.camera_id));
    }
  }
  for (const auto& [id, point] : model.points) {
    if (!point.xyz.allFinite() || !std::isfinite(point.error)) {
      Invalid(folder / "points3D", format("point {}", id), "is not finite");
    }
  }
}

ColmapModel ReadBinary(const fs::path& folder) {
  ColmapModel model;
  {
    BinaryReader in(folder / "cameras.bin");
    const uint64_t count = in.ReadCount("camera count", 24);
    for (uint64_t i = 0; i < count; ++i) {
      ColmapCamera camera;
      camera.id = in.Read<uint32_t>("camera id");
      const int model_id = in.Read<int32_t>("camera model");
      camera.model = ColmapModelName(model_id);
      if (camera.model.empty()) in.Fail(format("camera {} has the unknown model id {}", camera.id, model_id));
      camera.width = in.Read<uint64_t>("camera width");
      camera.height = in.Read<uint64_t>("camera height");
      camera.params.resize(ColmapModelParamCount(camera.model));
      for (double& p : camera.params) p = in.Read<double>("camera parameter");
      ValidateCamera(camera, folder / "cameras.bin");
      if (!model.cameras.emplace(camera.id, camera).second) in.Fail(format("camera {} appears twice", camera.id));
    }
    in.ExpectEnd();
  }
  {
    BinaryReader in(folder / "images.bin");
    const uint64_t count = in.ReadCount("image count", 64 + 2 + 8);
    for (uint64_t i = 0; i < count; ++i) {
      ColmapImage image;
      image.id = in.Read<uint32_t>("image id");
      const double qw = in.Read<double>("quaternion"), qx = in.Read<double>("quaternion"),
                   qy = in.Read<double>("quaternion"), qz = in.Read<double>("quaternion");
      image.cam_from_world_rotation = Eigen::Quaterniond(qw, qx, qy, qz);
      for (int k = 0; k < 3; ++k) image.cam_from_world_translation[k] = in.Read<double>("translation");
      image.camera_id = in.Read<uint32_t>("camera id");
      image.name = in.ReadName("image name");
      const uint64_t points = in.ReadCount("2D point count", 24);
      image.points2d.reserve(points);
      image.point3d_ids.reserve(points);
      for (uint64_t k = 0; k < points; ++k) {
        const double x = in.Read<double>("2D point"), y = in.Read<double>("2D point");
        image.points2d.emplace_back(x, y);
        image.point3d_ids.push_back(in.Read<uint64_t>("3D point id"));
      }
      ValidateImage(image, folder / "images.bin");
      if (!model.images.emplace(image.id, image).second) in.Fail(format("image {} appears twice", image.id));
    }
    in.ExpectEnd();
  }
  model.points = ReadColmapPointsBinary(folder / "points3D.bin");
  return model;
}

// Lines of a COLMAP text file without comments and blank lines, with their line numbers.
std::vector<std::pair<int, std::string>> DataLines(const fs::path& path, bool keep_blank) {
  std::ifstream in(path);
  if (!in) throw UserError(format("cannot read the COLMAP model file '{}'", path.string()));
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty() && line[0] == '#') continue;
    if (line.find_first_not_of(" \t") == std::string::npos && !keep_blank) continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

template <class T>
T Parse(std::istringstream& in, const fs::path& path, int line, const char* what) {
  T value;
  if (!(in >> value)) Invalid(path, format("line {}", line), format("has no valid {}", what));
  return value;
}

ColmapModel ReadText(const fs::path& folder) {
  ColmapModel model;
  const fs::path cameras_path = folder / "cameras.txt";
  for (const auto& [number, line] : DataLines(cameras_path, false)) {
    std::istringstream in(line);
    in.imbue(std::locale::classic());
    ColmapCamera camera;
    camera.id = Parse<uint32_t>(in, cameras_path, number, "camera id");
    camera.model = Parse<std::string>(in, cameras_path, number, "camera model");
    camera.width = Parse<uint64_t>(in, cameras_path, number, "width");
    camera.height = Parse<uint64_t>(in, cameras_path, number, "height");
    double p;
    while (in >> p) camera.params.push_back(p);
    if (!in.eof()) Invalid(cameras_path, format("line {}", number), "has a parameter that is not a number");
    ValidateCamera(camera, cameras_path);
    if (!model.cameras.emplace(camera.id, camera).second) {
      Invalid(cameras_path, format("line {}", number), format("repeats camera {}", camera.id));
    }
  }
  const fs::path images_path = folder / "images.txt";
  const auto image_lines = DataLines(images_path, true);
  for (size_t i = 0; i < image_lines.size(); ++i) {
    const auto& [number, line] = image_lines[i];
    if (line.find_first_not_of(" \t") == std::string::npos) continue;  // a blank line between records
    std::istringstream in(line);
    in.imbue(std::locale::classic());
    ColmapImage image;
    image.id = Parse<uint32_t>(in, images_path, number, "image id");
    double q[4];
    for (double& v : q) v = Parse<double>(in, images_path, number, "quaternion");
    image.cam_from_world_rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    for (int k = 0; k < 3; ++k)
      image.cam_from_world_translation[k] = Parse<double>(in, images_path, number, "translation");
    image.camera_id = Parse<uint32_t>(in, images_path, number, "camera id");
    std::getline(in >> std::ws, image.name);
    if (i + 1 < image_lines.size()) {
      std::istringstream points(image_lines[++i].second);
      points.imbue(std::locale::classic());
      double x, y;
      int64_t id;
      while (points >> x >> y >> id) {
        image.points2d.emplace_back(x, y);
        image.point3d_ids.push_back(id < 0 ? kNoPoint3D : static_cast<uint64_t>(id));
      }
      if (!points.eof()) Invalid(images_path, format("line {}", image_lines[i].first), "has a malformed 2D point");
    }
    ValidateImage(image, images_path);
    if (!model.images.emplace(image.id, image).second) {
      Invalid(images_path, format("line {}", number), format("repeats image {}", image.id));
    }
  }
  const fs::path points_path = folder / "points3D.txt";
  for (const auto& [number, line] : DataLines(points_path, false)) {
    std::istringstream in(line);
    in.imbue(std::locale::classic());
    ColmapPoint3D point;
    point.id = Parse<uint64_t>(in, points_path, number, "point id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = Parse<double>(in, points_path, number, "position");
    for (int k = 0; k < 3; ++k) {
      const int value = Parse<int>(in, points_path, number, "colour");
      if (value < 0 || value > 255) Invalid(points_path, format("line {}", number), "has a colour outside 0..255");
      point.rgb[k] = static_cast<uint8_t>(value);
    }
    point.error = Parse<double>(in, points_path, number, "error");
    uint32_t image_id, index;
    while (in >> image_id >> index) point.track.emplace_back(image_id, index);
    if (!in.eof()) Invalid(points_path, format("line {}", number), "has a malformed track");
    if (!model.points.emplace(point.id, point).second) {
      Invalid(points_path, format("line {}", number), format("repeats point {}", point.id));
    }
  }
  return model;
}

template <class T>
void Put(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(value));
}

}  // namespace

std::map<uint64_t, ColmapPoint3D> ReadColmapPointsBinary(const fs::path& file) {
  std::map<uint64_t, ColmapPoint3D> points;
  BinaryReader in(file);
  const uint64_t count = in.ReadCount("point count", 8 + 24 + 3 + 8 + 8);
  for (uint64_t i = 0; i < count; ++i) {
    ColmapPoint3D point;
    point.id = in.Read<uint64_t>("point id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = in.Read<double>("point position");
    for (int k = 0; k < 3; ++k) point.rgb[k] = in.Read<uint8_t>("point colour");
    point.error = in.Read<double>("point error");
    const uint64_t track = in.ReadCount("track length", 8);
    point.track.reserve(track);
    for (uint64_t k = 0; k < track; ++k) {
      const uint32_t image_id = in.Read<uint32_t>("track image id");
      point.track.emplace_back(image_id, in.Read<uint32_t>("track point index"));
    }
    if (!points.emplace(point.id, point).second) in.Fail(format("point {} appears twice", point.id));
  }
  in.ExpectEnd();
  return points;
}

int ColmapModelParamCount(const std::string& model) {
  for (const CameraModelInfo& info : kCameraModels) {
    if (model == info.name) return info.params;
  }
  return -1;
}

std::string ColmapModelName(int model_id) {
  for (const CameraModelInfo& info : kCameraModels) {
    if (model_id == info.id) return info.name;
  }
  return "";
}

PinholeCamera PinholeFromColmap(const ColmapCamera& camera, std::array<double, 4>* distortion) {
  PinholeCamera pinhole;
  pinhole.width = static_cast<int>(camera.width);
  pinhole.height = static_cast<int>(camera.height);
  *distortion = {};
  const std::vector<double>& p = camera.params;
  if (camera.model == "SIMPLE_PINHOLE" || camera.model == "SIMPLE_RADIAL" || camera.model == "RADIAL") {
    pinhole.fx = pinhole.fy = p[0], pinhole.cx = p[1], pinhole.cy = p[2];
    if (camera.model != "SIMPLE_PINHOLE") (*distortion)[0] = p[3];
    if (camera.model == "RADIAL") (*distortion)[1] = p[4];
  } else if (camera.model == "PINHOLE" || camera.model == "OPENCV") {
    pinhole.fx = p[0], pinhole.fy = p[1], pinhole.cx = p[2], pinhole.cy = p[3];
    if (camera.model == "OPENCV") *distortion = {p[4], p[5], p[6], p[7]};
  } else {
    throw UserError(
        format("camera {} is a {} camera, which photo2nerf does not undistort; give the photo folder "
               "instead and let photo2nerf run COLMAP",
               camera.id, camera.model));
  }
  return pinhole;
}

ColmapModel ReadColmapModelBinary(const fs::path& folder) {
  ColmapModel model = ReadBinary(folder);
  ValidateModel(model, folder);
  return model;
}

ColmapModel ReadColmapModelText(const fs::path& folder) {
  ColmapModel model = ReadText(folder);
  ValidateModel(model, folder);
  return model;
}

ColmapModel ReadColmapModel(const fs::path& folder) {
  if (fs::exists(folder / "cameras.bin")) return ReadColmapModelBinary(folder);
  if (fs::exists(folder / "cameras.txt")) return ReadColmapModelText(folder);
  throw UserError(format("'{}' holds no COLMAP model (cameras.bin or cameras.txt)", folder.string()));
}

void WriteColmapModelBinary(const ColmapModel& model, const fs::path& folder) {
  fs::create_directories(folder);
  std::string cameras, images, points;
  Put<uint64_t>(cameras, model.cameras.size());
  for (const auto& [id, camera] : model.cameras) {
    Put<uint32_t>(cameras, id);
    Put<int32_t>(cameras, ModelId(camera.model));
    Put<uint64_t>(cameras, camera.width);
    Put<uint64_t>(cameras, camera.height);
    for (const double p : camera.params) Put<double>(cameras, p);
  }
  Put<uint64_t>(images, model.images.size());
  for (const auto& [id, image] : model.images) {
    Put<uint32_t>(images, id);
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    for (const double v : {q.w(), q.x(), q.y(), q.z()}) Put<double>(images, v);
    for (int k = 0; k < 3; ++k) Put<double>(images, image.cam_from_world_translation[k]);
    Put<uint32_t>(images, image.camera_id);
    images.append(image.name);
    images.push_back('\0');
    Put<uint64_t>(images, image.points2d.size());
    for (size_t k = 0; k < image.points2d.size(); ++k) {
      Put<double>(images, image.points2d[k].x());
      Put<double>(images, image.points2d[k].y());
      Put<uint64_t>(images, image.point3d_ids[k]);
    }
  }
  Put<uint64_t>(points, model.points.size());
  for (const auto& [id, point] : model.points) {
    Put<uint64_t>(points, id);
    for (int k = 0; k < 3; ++k) Put<double>(points, point.xyz[k]);
    for (int k = 0; k < 3; ++k) Put<uint8_t>(points, point.rgb[k]);
    Put<double>(points, point.error);
    Put<uint64_t>(points, point.track.size());
    for (const auto& [image_id, index] : point.track) {
      Put<uint32_t>(points, image_id);
      Put<uint32_t>(points, index);
    }
  }
  WriteFileAtomic(folder / "cameras.bin", cameras);
  WriteFileAtomic(folder / "images.bin", images);
  WriteFileAtomic(folder / "points3D.bin", points);
}

void WriteColmapModelText(const ColmapModel& model, const fs::path& folder) {
  fs::create_directories(folder);
  std::ostringstream cameras, images, points;
  for (std::ostringstream* out : {&cameras, &images, &points}) {
    out->imbue(std::locale::classic());
    out->precision(17);
  }
  cameras << "# Camera list: CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
  for (const auto& [id, camera] : model.cameras) {
    cameras << id << ' ' << camera.model << ' ' << camera.width << ' ' << camera.height;
    for (const double p : camera.params) cameras << ' ' << p;
    cameras << '\n';
  }
  images << "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n# POINTS2D[] as (X, Y, POINT3D_ID)\n";
  for (const auto& [id, image] : model.images) {
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    const Eigen::Vector3d& t = image.cam_from_world_translation;
    images << id << ' ' << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << t.x() << ' ' << t.y() << ' '
           << t.z() << ' ' << image.camera_id << ' ' << image.name << '\n';
    for (size_t k = 0; k < image.points2d.size(); ++k) {
      images << (k ? " " : "") << image.points2d[k].x() << ' ' << image.points2d[k].y() << ' '
             << (image.point3d_ids[k] == kNoPoint3D ? int64_t{-1} : static_cast<int64_t>(image.point3d_ids[k]));
    }
    images << '\n';
  }
  points << "# POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
  for (const auto& [id, point] : model.points) {
    points << id << ' ' << point.xyz.x() << ' ' << point.xyz.y() << ' ' << point.xyz.z() << ' ' << int{point.rgb[0]}
           << ' ' << int{point.rgb[1]} << ' ' << int{point.rgb[2]} << ' ' << point.error;
    for (const auto& [image_id, index] : point.track) points << ' ' << image_id << ' ' << index;
    points << '\n';
  }
  WriteFileAtomic(folder / "cameras.txt", cameras.str());
  WriteFileAtomic(folder / "images.txt", images.str());
  WriteFileAtomic(folder / "points3D.txt", points.str());
}

}  // namespace p2n
