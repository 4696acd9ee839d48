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
// Writes 32-bit float linear values (OpenEXR, or any float format OpenImageIO writes by the extension).
void SaveFloatImageExr(const FloatImage& image, const std::filesystem::path& path);

// Peak signal-to-noise ratio for a peak of 1, in dB; std::invalid_argument when the sizes differ.
double Psnr(const FloatImage& a, const FloatImage& b);
// PSNR in dB of a mean squared error of values in [0, 1] (capped at 200 dB for a zero error).
double PsnrOfMse(double mse);
// The mean of per-view scores; NaN for none.
double Mean(const std::vector<double>& values);
// The q-quantile (0..1, nearest rank) of a non-empty list.
double Quantile(std::vector<double> values, double q);
// Structural similarity (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01, K2 0.03, peak 1) of
// the luminance-free per-channel form, averaged over pixels and channels; std::invalid_argument when the sizes
// differ.
double Ssim(const FloatImage& a, const FloatImage& b);
// The per-pixel error |a - b| averaged over channels, mapped by the inferno colour map from 0 (black) to
// `max_error` (yellow) and beyond: an RGB image of the same size.
FloatImage ErrorHeatMap(const FloatImage& a, const FloatImage& b, float max_error);

}  // namespace p2n
