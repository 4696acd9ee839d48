#pragma once
// An image as floats in [0, 1] (row-major, channels interleaved) for training and evaluation.

#include <filesystem>
#include <vector>

namespace p2n {

struct FloatImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
};

// Writes an 8-bit (or 16-bit when `sixteen_bits`) PNG; throws std::runtime_error naming the file.
void SaveFloatImage(const FloatImage& image, const std::filesystem::path& path, bool sixteen_bits = false);
// Peak signal-to-noise ratio for a peak of 1, in dB; std::invalid_argument when the sizes differ.
double Psnr(const FloatImage& a, const FloatImage& b);

}  // namespace p2n
