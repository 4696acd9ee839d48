#pragma once
// What one stage computed that a later stage of the same run needs again (the training views rendered by the
// trained field: the splat stage places its first splats from them, the export stage makes its point cloud from
// them), kept in memory for one Runner::Run. A value is found by a key that must name everything it depends on; a
// stage run alone finds nothing and computes the value itself, so results never depend on what ran before.

#include <any>
#include <map>
#include <memory>
#include <string>

namespace p2n {

class RunMemo {
 public:
  // The value kept under `key`, or nullptr when there is none of type T.
  template <typename T>
  std::shared_ptr<const T> Find(const std::string& key) const {
    const auto found = values_.find(key);
    if (found == values_.end()) return nullptr;
    const auto* value = std::any_cast<std::shared_ptr<const T>>(&found->second);
    return value != nullptr ? *value : nullptr;
  }
  template <typename T>
  void Keep(const std::string& key, std::shared_ptr<const T> value) {
    values_[key] = std::move(value);
  }

 private:
  std::map<std::string, std::any> values_;
};

}  // namespace p2n
