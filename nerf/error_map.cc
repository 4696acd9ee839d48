#include "nerf/error_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace p2n {

ErrorMap::ErrorMap(const std::vector<std::pair<int, int>>& sizes) {
  for (const auto& [width, height] : sizes) {
    if (width <= 0 || height <= 0) {
      throw std::invalid_argument("error map: an image of " + std::to_string(width) + "x" + std::to_string(height));
    }
    View view;
    view.width = width;
    view.height = height;
    view.cell_size = (std::max(width, height) + kCellsPerSide - 1) / kCellsPerSide;
    view.columns = (width + view.cell_size - 1) / view.cell_size;
    view.first_cell = static_cast<uint32_t>(errors_.size());
    const int rows = (height + view.cell_size - 1) / view.cell_size;
    for (int cell = 0; cell < view.columns * rows; ++cell) {
      cell_view_.push_back(static_cast<uint32_t>(views_.size()));
      errors_.push_back(1.0f);
    }
    views_.push_back(view);
    total_pixels_ += double(width) * height;
  }
  Rebuild();
}

int ErrorMap::CellWidth(const View& view, uint32_t local) const {
  return std::min(view.cell_size, view.width - static_cast<int>(local % view.columns) * view.cell_size);
}

int ErrorMap::CellHeight(const View& view, uint32_t local) const {
  return std::min(view.cell_size, view.height - static_cast<int>(local / view.columns) * view.cell_size);
}

double ErrorMap::CellPixels(uint32_t cell) const {
  const View& view = views_[cell_view_[cell]];
  const uint32_t local = cell - view.first_cell;
  return double(CellWidth(view, local)) * CellHeight(view, local);
}

void ErrorMap::Rebuild() {
  double weighted = 0;  // the sum over cells of error x pixels
  for (uint32_t c = 0; c < errors_.size(); ++c) weighted += errors_[c] * CellPixels(c);
  cumulative_.resize(errors_.size());
  double sum = 0;
  for (uint32_t c = 0; c < errors_.size(); ++c) {
    const double uniform = CellPixels(c) / total_pixels_;
    const double focused = weighted > 0 ? errors_[c] * CellPixels(c) / weighted : uniform;
    sum += kUniformShare * uniform + (1 - kUniformShare) * focused;
    cumulative_[c] = sum;
  }
}

ErrorMap::Draw ErrorMap::Sample(std::mt19937_64* random) const {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double u = unit(*random) * cumulative_.back();
  const uint32_t cell = static_cast<uint32_t>(std::min<size_t>(
      std::upper_bound(cumulative_.begin(), cumulative_.end(), u) - cumulative_.begin(), cumulative_.size() - 1));
  const View& view = views_[cell_view_[cell]];
  const uint32_t local = cell - view.first_cell;
  Draw draw;
  draw.view = cell_view_[cell];
  draw.cell = cell;
  draw.x = static_cast<int>(local % view.columns) * view.cell_size +
           std::uniform_int_distribution<int>(0, CellWidth(view, local) - 1)(*random);
  draw.y = static_cast<int>(local / view.columns) * view.cell_size +
           std::uniform_int_distribution<int>(0, CellHeight(view, local) - 1)(*random);
  const double probability = (cumulative_[cell] - (cell > 0 ? cumulative_[cell - 1] : 0.0)) / cumulative_.back();
  draw.weight = static_cast<float>(CellPixels(cell) / total_pixels_ / probability);
  return draw;
}

void ErrorMap::Record(uint32_t cell, float loss) {
  if (cell >= errors_.size() || !(loss >= 0) || !std::isfinite(loss)) return;
  errors_[cell] += kRecordRate * (loss - errors_[cell]);
}

void ErrorMap::Save(BinaryWriter* writer) const { writer->PutVector(errors_); }

void ErrorMap::Load(BinaryReader* reader) {
  std::vector<float> errors = reader->GetVector<float>(errors_.size());
  for (const float e : errors) {
    if (!(e >= 0) || !std::isfinite(e)) reader->Fail("an error-map cell holds " + std::to_string(e));
  }
  errors_ = std::move(errors);
  Rebuild();
}

}  // namespace p2n
