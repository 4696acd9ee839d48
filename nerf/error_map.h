#pragma once
// Error-driven ray sampling (instant-ngp's error map). Each training image is divided into cells (kCellsPerSide
// along its longer side, square cells), each with a running mean of the loss of the rays drawn in it. A pixel is
// drawn with the probability of a mixture, half uniform over all pixels and half in proportion to its cell's
// error, so that what the field renders worst is seen more often while every pixel keeps at least half its
// uniform chance. Each draw carries the weight (uniform probability) / (its probability): a loss weighted so has
// the uniform loss's expectation and gradient (importance sampling), with less variance where the errors are
// uneven. Deterministic for a given sequence of draws and records.

#include <cstddef>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "base/binary_io.h"

namespace p2n {

class ErrorMap {
 public:
  static constexpr int kCellsPerSide = 32;
  static constexpr float kUniformShare = 0.5f;  // of each draw's probability
  static constexpr float kRecordRate = 0.1f;    // a cell's error moves this far towards each loss recorded in it

  struct Draw {
    size_t view = 0;
    int x = 0, y = 0;   // the pixel
    uint32_t cell = 0;  // for Record()
    float weight = 1;   // uniform probability / this draw's probability
  };

  // Each view's width and height (pixels, positive). Every cell starts at the same error: the first draws are
  // uniform.
  explicit ErrorMap(const std::vector<std::pair<int, int>>& sizes);

  Draw Sample(std::mt19937_64* random) const;
  // Moves a cell's error towards a loss seen there (finite, non-negative; others are ignored). The draws follow
  // after the next Rebuild().
  void Record(uint32_t cell, float loss);
  // The sampling distribution from the current errors.
  void Rebuild();

  size_t cells() const { return errors_.size(); }
  float error(uint32_t cell) const { return errors_[cell]; }

  // The errors (the distribution is rebuilt on Load()).
  void Save(BinaryWriter* writer) const;
  void Load(BinaryReader* reader);

 private:
  struct View {
    int width, height, cell_size, columns;
    uint32_t first_cell;
  };
  // A cell's rectangle, clipped to its image (`local`: the cell's index within its view).
  int CellWidth(const View& view, uint32_t local) const;
  int CellHeight(const View& view, uint32_t local) const;
  double CellPixels(uint32_t cell) const;

  std::vector<View> views_;
  std::vector<uint32_t> cell_view_;  // each cell's view
  std::vector<float> errors_;
  std::vector<double> cumulative_;  // probability of cells [0, c] (the last is 1 but for rounding)
  double total_pixels_ = 0;
};

}  // namespace p2n
