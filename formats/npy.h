#pragma once
// NumPy arrays: .npy files and .npz archives (zip, stored or deflated), as datasets ship them (LLFF's
// poses_bounds.npy, the course data set's .npz). Little-endian float64, float32 and uint8 in C order; anything
// else, or a shape that does not match the data, is a UserError naming the file.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace p2n {

struct NpyArray {
  std::vector<size_t> shape;
  std::vector<double> values;  // converted to double, C order
  size_t size() const;
};

// Parses one .npy from its bytes; `source` names it in errors.
NpyArray ParseNpy(const std::string& bytes, const std::string& source);
NpyArray ReadNpy(const std::filesystem::path& path);
// Every array of an .npz archive, by name without ".npy".
std::map<std::string, NpyArray> ReadNpz(const std::filesystem::path& path);

}  // namespace p2n
