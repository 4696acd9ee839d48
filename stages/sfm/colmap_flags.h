#pragma once
// COLMAP's command-line option names change between versions (3.13 moved use_gpu, gpu_index, num_threads and
// max_image_size from SiftExtraction/SiftMatching to FeatureExtraction/FeatureMatching, with no aliases). The
// version is read from the program itself and the names are built from it, never hard-coded at call sites.

#include <filesystem>
#include <string>
#include <string_view>

namespace p2n {

struct ColmapVersion {
  int major = 0;
  int minor = 0;
  bool AtLeast(int want_major, int want_minor) const {
    return major > want_major || (major == want_major && minor >= want_minor);
  }
  std::string ToString() const { return std::to_string(major) + "." + std::to_string(minor); }
};

// Parses the banner COLMAP prints ("COLMAP 3.8 -- Structure-from-Motion ...", "COLMAP 3.14.0.dev0 -- ...").
// Throws UserError quoting the text when it holds no version.
ColmapVersion ParseColmapVersion(std::string_view banner);

// Runs `colmap help` (output to `log_file`) once per program and process, and parses its version;
// ExternalToolError naming the program when it cannot be run.
ColmapVersion DetectColmapVersion(const std::string& program, const std::filesystem::path& log_file);

// The option names for one COLMAP version, with their leading "--".
struct ColmapFlags {
  std::string extraction_use_gpu;
  std::string extraction_num_threads;
  std::string extraction_max_image_size;
  std::string extraction_max_num_features;
  std::string matching_use_gpu;
  std::string matching_num_threads;
};

ColmapFlags ColmapFlagsFor(const ColmapVersion& version);

}  // namespace p2n
