#pragma once
// Closed sets named as text (options, file fields, messages). An enum gets its names by specialising EnumNames
// beside its declaration, once:
//
//   enum class RenderSource { kAuto, kField, kSplats };
//   template <>
//   struct EnumNames<RenderSource> {
//     static constexpr std::pair<RenderSource, const char*> kValues[] = {
//         {RenderSource::kAuto, "auto"}, {RenderSource::kField, "field"}, {RenderSource::kSplats, "splats"}};
//   };
//
// and is then an option type (pipeline/options.h: its names are the option's choices) and a JSON field by name.

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace p2n {

template <class E>
struct EnumNames;

// The name of `value` ("?" for a value without one, which a specialisation that names every value never gives).
template <class E>
const char* EnumName(E value) {
  for (const auto& [each, name] : EnumNames<E>::kValues) {
    if (each == value) return name;
  }
  return "?";
}

// The value named `name`, or nothing.
template <class E>
std::optional<E> EnumFromName(std::string_view name) {
  for (const auto& [each, each_name] : EnumNames<E>::kValues) {
    if (name == each_name) return each;
  }
  return std::nullopt;
}

// Every name, in declaration order.
template <class E>
std::vector<std::string> EnumNameList() {
  std::vector<std::string> names;
  for (const auto& entry : EnumNames<E>::kValues) names.emplace_back(entry.second);
  return names;
}

// "a, b or c": the names for a message.
template <class E>
std::string EnumNamesText() {
  const std::vector<std::string> names = EnumNameList<E>();
  std::string text;
  for (size_t i = 0; i < names.size(); ++i) {
    text.append(i == 0 ? "" : i + 1 == names.size() ? " or " : ", ").append(names[i]);
  }
  return text;
}

}  // namespace p2n
