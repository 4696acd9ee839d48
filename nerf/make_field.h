#pragma once
// The field a config describes (its "otype": NgpField, VanillaField or BlockedField), for the trainer and the model
// file's reader: the one place that knows every kind of field, apart from the interface they share
// (nerf/radiance_field.h).

#include <cstdint>
#include <memory>

#include <nlohmann/json.hpp>

#include "nerf/radiance_field.h"

namespace p2n {

// The field a config describes; std::invalid_argument naming the bad field of the config.
template <typename T>
std::unique_ptr<RadianceField<T>> MakeField(const nlohmann::json& config, uint64_t seed);

extern template std::unique_ptr<RadianceField<float>> MakeField(const nlohmann::json&, uint64_t);
extern template std::unique_ptr<RadianceField<double>> MakeField(const nlohmann::json&, uint64_t);

}  // namespace p2n
