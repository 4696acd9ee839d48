#include "nerf/blocked_field.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "nerf/make_field.h"

namespace p2n {

template <typename T>
BlockedField<T>::BlockedField(Slabs slabs, std::vector<std::unique_ptr<RadianceField<T>>> fields)
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
  Slabs slabs;
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
