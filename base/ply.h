#pragma once
// The PLY container of every PLY file photo2nerf writes or reads (point clouds, meshes, splats, compressed splats):
// binary little-endian, its header made from and read into elements of named, typed properties. What the elements
// hold is each file's own (formats/ply.h, formats/mesh_io.h, splat/splat_ply.h, splat/compressed_ply.h).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace p2n {

struct PlyProperty {
  std::string type;  // "float", "uchar", ...; a list's item type
  std::string name;
  std::string list_count;  // a list's count type ("uchar"); empty for a scalar
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

// Scalar properties of one `type`, one a name.
std::vector<PlyProperty> PlyProperties(const std::string& type, const std::vector<std::string>& names);

// The bytes of a scalar of `type` (PLY's names and their sized aliases: "float", "float32", "uchar", "uint8", ...);
// 0 for a type PLY does not have.
size_t PlyTypeSize(const std::string& type);

// A binary little-endian header: the comments "written by photo2nerf" and `comments` (newlines become spaces), then
// the elements.
std::string PlyHeader(const std::vector<PlyElement>& elements, const std::vector<std::string>& comments = {});

// A header as read: its format line's words after "format", its elements, and where the body begins.
struct PlyLayout {
  std::string format;
  std::vector<PlyElement> elements;
  size_t body = 0;

  bool BinaryLittleEndian() const { return format == "binary_little_endian 1.0"; }
};
// The header at the start of `data`, comments left out (they may hold any text, "end_header" too); std::runtime_error
// saying what is wrong: no "ply" line, no end_header, an element count or a property line that cannot be read.
PlyLayout ReadPlyHeader(std::string_view data);

// Which of `count` records to write first: Assimp's PLY reader (5.2, Debian 12's; its issue #5341) skips a line
// end or space right after "end_header\n" even in a binary file, and then reads every record one byte off. The
// writers swap the first record with the first whose first byte (of the float `first_value(i)`) is none of those;
// 0 when that one is, or none is.
template <class FirstValue>
size_t LeadingRecord(size_t count, FirstValue first_value) {
  for (size_t i = 0; i < count; ++i) {
    const float value = first_value(i);
    uint8_t byte;
    std::memcpy(&byte, &value, 1);  // little-endian: the first byte written
    if (byte != 0 && byte != ' ' && (byte < '\t' || byte > '\r')) return i;
  }
  return 0;
}
// With records 0 and `first` trading places: the record at place i of the file, and the place of record i.
inline size_t TradedPlace(size_t i, size_t first) { return i == 0 ? first : i == first ? 0 : i; }

}  // namespace p2n
