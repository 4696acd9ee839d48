#include "base/ply.h"

#include <algorithm>
#include <charconv>
#include <map>
#include <sstream>
#include <stdexcept>

namespace p2n {

std::vector<PlyProperty> PlyProperties(const std::string& type, const std::vector<std::string>& names) {
  std::vector<PlyProperty> properties;
  for (const std::string& name : names) properties.push_back({type, name, ""});
  return properties;
}

size_t PlyTypeSize(const std::string& type) {
  static const std::map<std::string, size_t> kSizes = {{"char", 1},  {"int8", 1},    {"uchar", 1},  {"uint8", 1},
                                                       {"short", 2}, {"int16", 2},   {"ushort", 2}, {"uint16", 2},
                                                       {"int", 4},   {"int32", 4},   {"uint", 4},   {"uint32", 4},
                                                       {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto size = kSizes.find(type);
  return size == kSizes.end() ? 0 : size->second;
}

std::string PlyHeader(const std::vector<PlyElement>& elements, const std::vector<std::string>& comments) {
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by photo2nerf\n";
  for (std::string comment : comments) {
    // One line each, whatever it holds: other readers end a line at '\r' too.
    std::replace_if(
        comment.begin(), comment.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    header += "comment " + comment + "\n";
  }
  for (const PlyElement& element : elements) {
    header += "element " + element.name + " " + std::to_string(element.count) + "\n";
    for (const PlyProperty& property : element.properties) {
      header += "property " + (property.list_count.empty() ? "" : "list " + property.list_count + " ") + property.type +
                " " + property.name + "\n";
    }
  }
  return header + "end_header\n";
}

namespace {

// One line of the header after "ply", read into `layout`.
void ReadHeaderLine(std::string_view line, PlyLayout* layout) {
  std::istringstream words{std::string(line)};
  std::string word;
  words >> word;
  if (word == "format") {
    std::getline(words >> std::ws, layout->format);
  } else if (word == "element") {
    PlyElement element;
    std::string count;
    words >> element.name >> count;
    const auto [end, error] = std::from_chars(count.data(), count.data() + count.size(), element.count);
    if (element.name.empty() || count.empty() || error != std::errc() || end != count.data() + count.size()) {
      throw std::runtime_error("the count of element '" + element.name + "' cannot be read");
    }
    layout->elements.push_back(std::move(element));
  } else if (word == "property") {
    PlyProperty property;
    words >> property.type;
    if (property.type == "list") words >> property.list_count >> property.type;
    words >> property.name;
    if (property.name.empty() || layout->elements.empty()) {
      throw std::runtime_error("the property line '" + std::string(line) + "' cannot be read");
    }
    layout->elements.back().properties.push_back(std::move(property));
  }
}

}  // namespace

PlyLayout ReadPlyHeader(std::string_view data) {
  if (!data.starts_with("ply\n")) throw std::runtime_error("not a PLY file");
  PlyLayout layout;
  size_t at = 4;
  while (true) {
    const size_t newline = data.find('\n', at);
    if (newline == std::string_view::npos) throw std::runtime_error("the header has no end_header");
    const std::string_view line = data.substr(at, newline - at);
    at = newline + 1;
    if (line == "end_header") break;
    if (!line.starts_with("comment ")) ReadHeaderLine(line, &layout);
  }
  layout.body = at;
  return layout;
}

}  // namespace p2n
