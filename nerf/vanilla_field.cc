#include "nerf/vanilla_field.h"

#include <stdexcept>

#include "base/declared_fields.h"

namespace p2n {

nlohmann::json VanillaFieldConfig::ToJson() const {
  nlohmann::json json = FieldsToJson(*this);
  json["otype"] = "VanillaField";
  json["position_encoding"] = {{"otype", "Frequency"}, {"levels", position_levels}, {"include_input", true}};
  json["direction_encoding"] = {{"otype", "Frequency"}, {"levels", direction_levels}, {"include_input", true}};
  json["skip_after"] = layers / 2;
  json["density_activation"] = "ReLU";
  return json;
}

VanillaFieldConfig VanillaFieldConfig::FromJson(const nlohmann::json& json) {
  VanillaFieldConfig config;
  ReadFields(json, &config, {"otype", "position_encoding", "direction_encoding", "skip_after", "density_activation"},
             "VanillaField config");
  if (config.layers < 2 || config.layers % 2 != 0) {
    throw std::invalid_argument("VanillaField config: layers must be even and at least 2");
  }
  CheckDerivedKeys(json, config.ToJson(),
                   {"position_encoding", "direction_encoding", "skip_after", "density_activation"},
                   "VanillaField config");
  return config;
}

template <typename T>
VanillaField<T>::VanillaField(const VanillaFieldConfig& config, uint64_t seed)
    : config_(config),
      position_encoding_(3, config.position_levels),
      direction_encoding_(3, config.direction_levels),
      first_half_({position_encoding_.output_dims(), config.width, config.width, config.layers / 2 - 1,
                   OutputActivation::kRelu},
                  seed),
      second_half_({config.width + position_encoding_.output_dims(), config.width, config.width, config.layers / 2 - 1,
                    OutputActivation::kRelu},
                   seed + 1),
      head_({config.width, 1 + config.width, config.width, 0, OutputActivation::kNone}, seed + 2),
      colour_({config.width + direction_encoding_.output_dims(), 3, config.colour_width, 1, OutputActivation::kSigmoid},
              seed + 3) {}

template <typename T>
void VanillaField<T>::Trunk(const Matrix& positions, Matrix* encoded, Matrix* head,
                            typename Mlp<T>::Cache* caches) const {
  position_encoding_.Forward((T(2) * positions.array() - T(1)).matrix(), encoded);
  Matrix first, second_in(config_.width + encoded->rows(), positions.cols()), second;
  first_half_.Forward(*encoded, &first, &caches[0]);
  second_in << first, *encoded;
  second_half_.Forward(second_in, &second, &caches[1]);
  head_.Forward(second, head, &caches[2]);
}

template <typename T>
void VanillaField<T>::Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
                              Cache* cache) const {
  cache->positions = positions;
  cache->mlps.resize(4);
  Trunk(positions, &cache->encoded, &cache->hidden, cache->mlps.data());
  *density = cache->hidden.topRows(1).cwiseMax(T(0));
  Matrix encoded_direction;
  direction_encoding_.Forward(directions, &encoded_direction);
  cache->colour_in.resize(config_.width + encoded_direction.rows(), positions.cols());
  cache->colour_in << cache->hidden.bottomRows(config_.width), encoded_direction;
  colour_.Forward(cache->colour_in, rgb, &cache->mlps[3]);
}

template <typename T>
void VanillaField<T>::Density(const Matrix& positions, Matrix* density) const {
  Matrix encoded, head;
  typename Mlp<T>::Cache caches[3];
  Trunk(positions, &encoded, &head, caches);
  *density = head.topRows(1).cwiseMax(T(0));
}

template <typename T>
void VanillaField<T>::Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                               Matrix* d_encoded) const {
  d_encoded->resize(0, 0);
  T* d_first = d_dense;
  T* d_second = d_first + first_half_.num_params();
  T* d_head = d_second + second_half_.num_params();
  T* d_colour = d_head + head_.num_params();
  Matrix d_colour_in, d_head_out(cache.hidden.rows(), cache.hidden.cols()), d_second_out, d_second_in;
  colour_.Backward(cache.mlps[3], d_rgb, d_colour, &d_colour_in);
  d_head_out.topRows(1) = (cache.hidden.topRows(1).array() > T(0)).select(d_density, T(0));
  d_head_out.bottomRows(config_.width) = d_colour_in.topRows(config_.width);
  head_.Backward(cache.mlps[2], d_head_out, d_head, &d_second_out);
  second_half_.Backward(cache.mlps[1], d_second_out, d_second, &d_second_in);
  first_half_.Backward(cache.mlps[0], d_second_in.topRows(config_.width), d_first, nullptr);
}

template <typename T>
std::vector<ParamBlock<T>> VanillaField<T>::DenseParams() {
  std::vector<ParamBlock<T>> blocks;
  for (Mlp<T>* mlp : {&first_half_, &second_half_, &head_, &colour_}) {
    blocks.push_back({mlp->params(), static_cast<size_t>(mlp->num_params())});
  }
  return blocks;
}

template class VanillaField<float>;
template class VanillaField<double>;

}  // namespace p2n
