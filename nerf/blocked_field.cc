#include "nerf/blocked_field.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "base/float_image.h"

namespace p2n {

namespace {

// A model file's slabs: at most this many (each a whole field).
constexpr int kMaxSlabs = 256;

}  // namespace

int FieldSlabs::SlabOf(double coordinate) const {
  return static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), coordinate) - cuts.begin());
}

FieldSlabs CutIntoSlabs(const Eigen::Matrix3Xd& points, int count) {
  if (count < 1 || count > kMaxSlabs) {
    throw std::invalid_argument("CutIntoSlabs: " + std::to_string(count) + " slabs (1 to " + std::to_string(kMaxSlabs) +
                                ")");
  }
  FieldSlabs slabs;
  if (count == 1 || points.cols() == 0) return slabs;
  std::vector<std::vector<double>> coordinates(3);
  double widest = -1;
  for (int a = 0; a < 3; ++a) {
    coordinates[a].assign(points.row(a).begin(), points.row(a).end());
    const double spread = Quantile(coordinates[a], 0.95) - Quantile(coordinates[a], 0.05);
    if (spread > widest) widest = spread, slabs.axis = a;
  }
  for (int b = 1; b < count; ++b) {
    const double cut = Quantile(coordinates[slabs.axis], double(b) / count);
    if (slabs.cuts.empty() || cut > slabs.cuts.back()) slabs.cuts.push_back(cut);  // equal quantiles: one cut
  }
  return slabs;
}

template <typename T>
BlockedField<T>::BlockedField(FieldSlabs slabs, std::vector<std::unique_ptr<RadianceField<T>>> fields)
    : slabs_(std::move(slabs)), fields_(std::move(fields)) {
  const std::string what = "BlockedField: ";
  if (slabs_.axis < 0 || slabs_.axis > 2) throw std::invalid_argument(what + "axis must be 0, 1 or 2");
  if (slabs_.count() > kMaxSlabs) throw std::invalid_argument(what + "at most " + std::to_string(kMaxSlabs) + " slabs");
  if (static_cast<int>(fields_.size()) != slabs_.count()) {
    throw std::invalid_argument(what + std::to_string(fields_.size()) + " fields for " +
                                std::to_string(slabs_.count()) + " slabs");
  }
  for (size_t b = 0; b < slabs_.cuts.size(); ++b) {
    if (!std::isfinite(slabs_.cuts[b]) || (b > 0 && !(slabs_.cuts[b] > slabs_.cuts[b - 1]))) {
      throw std::invalid_argument(what + "the cuts must be finite and ascending");
    }
  }
  for (const auto& field : fields_) {
    if (field == nullptr) throw std::invalid_argument(what + "a slab has no field");
  }
}

template <typename T>
std::unique_ptr<BlockedField<T>> BlockedField<T>::FromJson(const nlohmann::json& config, uint64_t seed) {
  FieldSlabs slabs;
  slabs.axis = config.at("axis").get<int>();
  slabs.cuts = config.at("cuts").get<std::vector<double>>();
  const nlohmann::json& configs = config.at("fields");
  if (!configs.is_array() || static_cast<int>(configs.size()) != slabs.count() || slabs.count() > kMaxSlabs) {
    throw std::invalid_argument("BlockedField config: \"fields\" must hold one config a slab (" +
                                std::to_string(slabs.count()) + ")");
  }
  std::vector<std::unique_ptr<RadianceField<T>>> fields;
  for (const nlohmann::json& field : configs) {
    // One level: a block's field is never itself blocked (and a hostile file cannot nest them without end).
    if (field.is_object() && field.value("otype", "") == "BlockedField") {
      throw std::invalid_argument("BlockedField config: a slab's field cannot be a BlockedField");
    }
    fields.push_back(MakeField<T>(field, seed++));
  }
  return std::make_unique<BlockedField>(std::move(slabs), std::move(fields));
}

template <typename T>
nlohmann::json BlockedField<T>::Config() const {
  nlohmann::json configs = nlohmann::json::array();
  for (const auto& field : fields_) configs.push_back(field->Config());
  return {{"otype", "BlockedField"}, {"axis", slabs_.axis}, {"cuts", slabs_.cuts}, {"fields", configs}};
}

template <typename T>
template <typename Answer>
void BlockedField<T>::Route(const Matrix& positions, const Answer& answer) const {
  std::vector<std::vector<Eigen::Index>> columns(fields_.size());
  for (Eigen::Index i = 0; i < positions.cols(); ++i) {
    columns[slabs_.SlabOf(static_cast<double>(positions(slabs_.axis, i)))].push_back(i);
  }
  for (size_t b = 0; b < fields_.size(); ++b) {
    if (!columns[b].empty()) answer(*fields_[b], columns[b]);
  }
}

template <typename T>
void BlockedField<T>::Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
                              Cache* cache) const {
  *cache = Cache();
  Render(positions, directions, density, rgb);
}

template <typename T>
void BlockedField<T>::Render(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb) const {
  density->resize(1, positions.cols());
  rgb->resize(3, positions.cols());
  Route(positions, [&](const RadianceField<T>& field, const std::vector<Eigen::Index>& columns) {
    if (static_cast<Eigen::Index>(columns.size()) == positions.cols()) {
      field.Render(positions, directions, density, rgb);
      return;
    }
    Matrix slab_density, slab_rgb;
    field.Render(positions(Eigen::all, columns).eval(), directions(Eigen::all, columns).eval(), &slab_density,
                 &slab_rgb);
    (*density)(Eigen::all, columns) = slab_density;
    (*rgb)(Eigen::all, columns) = slab_rgb;
  });
}

template <typename T>
void BlockedField<T>::Density(const Matrix& positions, Matrix* density) const {
  density->resize(1, positions.cols());
  Route(positions, [&](const RadianceField<T>& field, const std::vector<Eigen::Index>& columns) {
    if (static_cast<Eigen::Index>(columns.size()) == positions.cols()) {
      field.Density(positions, density);
      return;
    }
    Matrix slab_density;
    field.Density(positions(Eigen::all, columns).eval(), &slab_density);
    (*density)(Eigen::all, columns) = slab_density;
  });
}

template <typename T>
void BlockedField<T>::Backward(const Cache&, const Matrix&, const Matrix&, T*, Matrix*) const {
  throw std::logic_error("BlockedField::Backward: a field by blocks is trained block by block, never whole");
}

template <typename T>
std::vector<ParamBlock<T>> BlockedField<T>::DenseParams() {
  std::vector<ParamBlock<T>> blocks;
  for (const auto& field : fields_) {
    for (const ParamBlock<T>& block : field->DenseParams()) blocks.push_back(block);
    if (Encoding<T>* encoding = field->TrainableEncoding()) {
      blocks.push_back({encoding->params(), encoding->num_params()});
    }
  }
  return blocks;
}

template class BlockedField<float>;
template class BlockedField<double>;

}  // namespace p2n
