#pragma once
// Helpers for the libFuzzer targets: inputs that readers take as files are written to a per-process folder
// in /dev/shm (memory), and only the typed errors a reader may throw for bad input are accepted.

#include <unistd.h>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace p2n::fuzz {

inline std::filesystem::path ScratchDir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path path = std::filesystem::path("/dev/shm") / ("p2n_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(path);
    return path;
  }();
  return dir;
}

inline void WriteBytes(const std::filesystem::path& path, const uint8_t* data, size_t size) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

// Splits the input into `parts` pieces at the positions given by its first bytes.
inline std::vector<std::string> Split(const uint8_t* data, size_t size, int parts) {
  std::vector<std::string> pieces;
  if (size < static_cast<size_t>(parts)) return std::vector<std::string>(parts);
  const uint8_t* body = data + parts - 1;
  size_t left = size - (parts - 1), offset = 0;
  for (int i = 0; i < parts - 1; ++i) {
    const size_t length = left == 0 ? 0 : (static_cast<size_t>(data[i]) * left) / 255;
    pieces.emplace_back(reinterpret_cast<const char*>(body + offset), length);
    offset += length;
    left -= length;
  }
  pieces.emplace_back(reinterpret_cast<const char*>(body + offset), left);
  return pieces;
}

}  // namespace p2n::fuzz
