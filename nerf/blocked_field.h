#pragma once
// A field trained by spatial blocks (`train.blocks`): the unit cube cut into slabs along one axis (base/slabs.h), each
// slab's field trained alone on the views that see it, and every point answered by the field of the slab it lies in
// (Mega-NeRF's routing, with slabs for its cells). Each block's field models the whole of its views' rays; only its
// own slab of it is ever shown, so the others' fit where its views saw little does not matter.
//
// The composite renders, meshes and bakes into splats like any field and is stored in model.bin (its config lists
// the slabs and each block's config; its parameters are each block's dense parameters and encoding in turn), but it
// is not trained whole: the blocks are trained one by one, so it has no gradient of its own.

#include <memory>
#include <vector>

#include "base/slabs.h"
#include "nerf/radiance_field.h"

namespace p2n {

template <typename T>
class BlockedField : public RadianceField<T> {
 public:
  using typename RadianceField<T>::Matrix;
  using typename RadianceField<T>::Cache;

  // One field a slab; std::invalid_argument when the counts differ, the cuts are not ascending or a field is null.
  BlockedField(Slabs slabs, std::vector<std::unique_ptr<RadianceField<T>>> fields);
  // From Config()'s JSON: {"otype": "BlockedField", "axis", "cuts", "fields": [each slab's config]}.
  static std::unique_ptr<BlockedField> FromJson(const nlohmann::json& config, uint64_t seed);

  nlohmann::json Config() const override;
  // Leaves `cache` empty: Backward() is not defined.
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
               Cache* cache) const override;
  void Render(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb) const override;
  void Density(const Matrix& positions, Matrix* density) const override;
  // std::logic_error: the blocks are trained one by one (stages/fitting/train_blocks.h), never the composite.
  void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                Matrix* d_encoded) const override;
  // Each slab's dense parameters, then its encoding's, slab after slab.
  std::vector<ParamBlock<T>> DenseParams() override;

  const Slabs& slabs() const { return slabs_; }
  RadianceField<T>& field(int slab) { return *fields_[slab]; }

 private:
  // Calls answer(field, columns) for each slab holding some of `positions`' columns (ascending), with its field.
  template <typename Answer>
  void Route(const Matrix& positions, const Answer& answer) const;

  Slabs slabs_;
  std::vector<std::unique_ptr<RadianceField<T>>> fields_;
};

extern template class BlockedField<float>;
extern template class BlockedField<double>;

}  // namespace p2n
