#include "nerf/nerf_model.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <optional>

#include "base/file_util.h"
#include "base/json_number.h"
#include "nerf/make_field.h"

namespace p2n {
namespace {

constexpr char kModelMagic[] = "P2NMODEL";

std::runtime_error FileError(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error("cannot " + what + " '" + path.string() + "': " + std::strerror(errno));
}

}  // namespace

const char* SceneSpaceName(SceneSpace space) {
  switch (space) {
    case SceneSpace::kBounded:
      return "bounded";
    case SceneSpace::kUnbounded:
      return "unbounded";
    case SceneSpace::kForward:
      return "forward";
  }
  return "?";
}

SceneSpace SceneSpaceFromName(const std::string& name) {
  for (const SceneSpace space : {SceneSpace::kBounded, SceneSpace::kUnbounded, SceneSpace::kForward}) {
    if (name == SceneSpaceName(space)) return space;
  }
  throw std::invalid_argument("unknown scene space '" + name + "' (bounded, unbounded or forward)");
}

Eigen::Matrix3d FieldPointJacobian(const NerfModel& model, const Eigen::Vector3d& world) {
  if (model.space == SceneSpace::kBounded) return 0.5 * Eigen::Matrix3d::Identity();
  if (model.space == SceneSpace::kForward) return 0.5 * ForwardNdcJacobian(model.forward, world);
  Eigen::Index axis;
  const double norm = world.cwiseAbs().maxCoeff(&axis);
  if (norm <= 1) return 0.25 * Eigen::Matrix3d::Identity();
  // contracted = g(norm) world with g(n) = 2/n - 1/n^2, and norm = |world[axis]|.
  const double g = (2 - 1 / norm) / norm, slope = (2 / norm - 2) / (norm * norm);
  Eigen::Matrix3d jacobian = g * Eigen::Matrix3d::Identity();
  jacobian.col(axis) += slope * (world[axis] > 0 ? 1.0 : -1.0) * world;
  return 0.25 * jacobian;
}

void WriteModel(const NerfModel& model, BinaryWriter* writer, bool occupancy_densities) {
  writer->PutBytes(kModelMagic, 8);
  writer->Put<uint32_t>(kModelFormatVersion);
  nlohmann::json header = {{"field", model.field->Config()},
                           {"occupancy_resolution", model.occupancy.resolution()},
                           {"occupancy_densities", occupancy_densities},
                           {"background", model.background},
                           {"space", SceneSpaceName(model.space)},
                           {"march_step", model.march_step},
                           {"stratified_samples", model.stratified_samples},
                           {"info", model.info}};
  if (model.space == SceneSpace::kForward) header["forward_frame"] = ForwardFrameJson(model.forward);
  writer->PutString(header.dump());
  for (const ParamBlock<float>& block : model.field->DenseParams()) writer->PutArray(block.data, block.size);
  Encoding<float>* encoding = model.field->TrainableEncoding();
  if (encoding != nullptr) writer->PutArray(encoding->params(), encoding->num_params());
  if (occupancy_densities) writer->PutVector(model.occupancy.densities());
  writer->PutVector(model.occupancy.bits());
}

NerfModel ReadModel(BinaryReader* reader) {
  reader->ExpectMagic(kModelMagic, "a photo2nerf model (model.bin)");
  const uint32_t version = reader->Get<uint32_t>();
  if (version > kModelFormatVersion) {
    reader->Fail("it has format version " + std::to_string(version) + " and this photo2nerf reads up to " +
                 std::to_string(kModelFormatVersion) + "; use a newer photo2nerf, or retrain the model");
  }
  if (version == 0) reader->Fail("format version 0 does not exist");
  NerfModel model;
  try {
    const nlohmann::json header = nlohmann::json::parse(reader->GetString());
    model.field = MakeField<float>(header.at("field"), 0);
    model.background = header.at("background").get<std::array<float, 3>>();
    model.march_step = header.at("march_step").get<double>();
    // Models written before forward-facing scenes say "contracted" instead of "space".
    model.space = header.contains("space")            ? SceneSpaceFromName(header.at("space").get<std::string>())
                  : header.value("contracted", false) ? SceneSpace::kUnbounded
                                                      : SceneSpace::kBounded;
    if (model.space == SceneSpace::kForward) model.forward = ForwardFrameFromJson(header.at("forward_frame"));
    const std::optional<int> stratified = JsonInteger<int>(header.value("stratified_samples", nlohmann::json(0)));
    if (!stratified || *stratified < 0 || *stratified > 65536) reader->Fail("stratified_samples must be 0..65536");
    model.stratified_samples = *stratified;
    model.info = header.value("info", nlohmann::json::object());
    const int resolution = JsonInteger<int>(header.at("occupancy_resolution")).value_or(0);
    if (!(model.march_step > 0 && model.march_step < 4)) reader->Fail("march_step must be in (0, 4)");
    for (ParamBlock<float>& block : model.field->DenseParams()) {
      const std::vector<float> values = reader->GetVector<float>(block.size);
      std::copy(values.begin(), values.end(), block.data);
    }
    if (Encoding<float>* encoding = model.field->TrainableEncoding()) {
      const std::vector<float> values = reader->GetVector<float>(encoding->num_params());
      std::copy(values.begin(), values.end(), encoding->params());
    }
    if (resolution < 1 || resolution > 1024) reader->Fail("occupancy_resolution must be 1..1024");
    const size_t cells = size_t(resolution) * resolution * resolution;
    // Version 1 kept the densities always.
    std::vector<float> densities;
    if (version < 2 || header.at("occupancy_densities").get<bool>()) densities = reader->GetVector<float>(cells);
    std::vector<uint8_t> bits = reader->GetVector<uint8_t>((cells + 7) / 8);
    model.occupancy = densities.empty() ? OccupancyGrid(resolution, std::move(bits))
                                        : OccupancyGrid(resolution, std::move(densities), std::move(bits));
  } catch (const nlohmann::json::exception& error) {
    reader->Fail(std::string("its header: ") + error.what());
  } catch (const std::invalid_argument& error) {
    reader->Fail(error.what());
  }
  return model;
}

void SaveModel(const NerfModel& model, const std::filesystem::path& path) {
  BinaryWriter writer;
  WriteModel(model, &writer, false);
  WriteBinaryFileAtomic(path, writer.buffer());
}

NerfModel LoadModel(const std::filesystem::path& path) {
  BinaryReader reader(ReadBinaryFile(path), path.string());
  NerfModel model = ReadModel(&reader);
  if (!reader.AtEnd()) reader.Fail("there are bytes after the model");
  return model;
}

std::vector<char> ReadBinaryFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "open");
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace p2n
