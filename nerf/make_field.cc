#include "nerf/make_field.h"

#include <stdexcept>

#include "nerf/blocked_field.h"
#include "nerf/ngp_field.h"
#include "nerf/vanilla_field.h"

namespace p2n {

template <typename T>
std::unique_ptr<RadianceField<T>> MakeField(const nlohmann::json& config, uint64_t seed) {
  const std::string otype = config.is_object() ? config.value("otype", "") : "";
  if (otype == "NgpField") return std::make_unique<NgpField<T>>(NgpFieldConfig::FromJson(config), seed);
  if (otype == "VanillaField") return std::make_unique<VanillaField<T>>(VanillaFieldConfig::FromJson(config), seed);
  if (otype == "BlockedField") return BlockedField<T>::FromJson(config, seed);
  throw std::invalid_argument(
      "field config: \"otype\" must be \"NgpField\", \"VanillaField\" or \"BlockedField\", not \"" + otype + "\"");
}

template std::unique_ptr<RadianceField<float>> MakeField(const nlohmann::json&, uint64_t);
template std::unique_ptr<RadianceField<double>> MakeField(const nlohmann::json&, uint64_t);

}  // namespace p2n
