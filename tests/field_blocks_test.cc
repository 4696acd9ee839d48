// A field by blocks: each point answered by its slab's field, the slabs cut by the points' quantiles, the views of a
// slab, the blocks' models made one, and model.bin keeping the composite.

#include <catch2/catch.hpp>

#include <random>
#include <stdexcept>

#include "nerf/field_blocks.h"
#include "nerf/make_field.h"
#include "nerf/nerf_model.h"
#include "nerf/ngp_field.h"

namespace p2n::testing {
namespace {

using Matrix = Eigen::MatrixXf;

NgpFieldConfig SmallConfig() {
  NgpFieldConfig config;
  config.grid.levels = 4;
  config.grid.log2_table_size = 10;
  config.grid.finest_resolution = 32;
  return config;
}

// Two slabs cut at x = 0.4, each an ngp field of its own seed with grids made large enough to tell apart.
std::unique_ptr<BlockedField<float>> TwoSlabs() {
  std::vector<std::unique_ptr<RadianceField<float>>> fields;
  for (uint64_t seed : {3, 4}) {
    auto field = std::make_unique<NgpField<float>>(SmallConfig(), seed);
    for (size_t k = 0; k < field->encoding().num_params(); ++k) {
      field->encoding().params()[k] = 0.7f * std::sin(0.3f * k + seed);
    }
    fields.push_back(std::move(field));
  }
  return std::make_unique<BlockedField<float>>(Slabs{0, {0.4}}, std::move(fields));
}

void RandomSamples(int count, Matrix* positions, Matrix* directions) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(0, 1);
  positions->resize(3, count);
  directions->resize(3, count);
  for (int i = 0; i < count; ++i) {
    positions->col(i) << unit(random), unit(random), unit(random);
    directions->col(i) = Eigen::Vector3f(unit(random) - 0.5f, unit(random) - 0.5f, 1).normalized();
  }
}

}  // namespace

TEST_CASE("a field by blocks answers each point from the field of its slab", "[blocks]") {
  auto blocked = TwoSlabs();
  Matrix positions, directions;
  RandomSamples(200, &positions, &directions);
  Matrix density, rgb, forward_density, forward_rgb, only_density;
  blocked->Render(positions, directions, &density, &rgb);
  RadianceField<float>::Cache cache;
  blocked->Forward(positions, directions, &forward_density, &forward_rgb, &cache);
  blocked->Density(positions, &only_density);
  REQUIRE(density.cols() == 200);
  int in_second = 0;
  for (int slab = 0; slab < 2; ++slab) {
    Matrix own_density, own_rgb, own_only;
    blocked->field(slab).Render(positions, directions, &own_density, &own_rgb);
    blocked->field(slab).Density(positions, &own_only);
    for (int i = 0; i < positions.cols(); ++i) {
      if ((positions(0, i) >= 0.4f) != (slab == 1)) continue;
      in_second += slab;
      CHECK(density(0, i) == Approx(own_density(0, i)).epsilon(1e-5));
      CHECK(only_density(0, i) == Approx(own_only(0, i)).epsilon(1e-5));
      for (int c = 0; c < 3; ++c) CHECK(rgb(c, i) == Approx(own_rgb(c, i)).epsilon(1e-5));
    }
  }
  CHECK(in_second > 50);
  CHECK(in_second < 150);
  CHECK(forward_density == density);
  CHECK(forward_rgb == rgb);
  // The two fields differ, so the routing is seen: the first slab's field elsewhere gives another density.
  Matrix first_density, first_rgb;
  blocked->field(0).Render(positions, directions, &first_density, &first_rgb);
  CHECK((first_density - density).cwiseAbs().maxCoeff() > 1e-3f);
  CHECK_THROWS_AS(blocked->Backward(cache, density, rgb, nullptr, nullptr), std::logic_error);
}

TEST_CASE("model.bin keeps a field by blocks, and refuses a damaged one's config", "[blocks]") {
  NerfModel model;
  model.field = TwoSlabs();
  model.march_step = 0.01;
  BinaryWriter writer;
  WriteModel(model, &writer, false);
  BinaryReader reader(writer.buffer(), "model.bin");
  const NerfModel read = ReadModel(&reader);
  CHECK(reader.AtEnd());
  CHECK(read.field->Config() == model.field->Config());
  Matrix positions, directions, density, rgb, read_density, read_rgb;
  RandomSamples(64, &positions, &directions);
  model.field->Render(positions, directions, &density, &rgb);
  read.field->Render(positions, directions, &read_density, &read_rgb);
  CHECK(read_density == density);
  CHECK(read_rgb == rgb);

  const nlohmann::json config = model.field->Config();
  const auto refused = [](nlohmann::json bad, const std::string& why) {
    CHECK_THROWS_WITH(MakeField<float>(bad, 0), Catch::Contains(why));
  };
  nlohmann::json bad = config;
  bad["cuts"] = {0.4, 0.6};
  refused(bad, "one config a slab");
  bad = config;
  bad["axis"] = 3;
  refused(bad, "axis");
  bad = config;
  bad["cuts"] = {0.4, 0.2};
  bad["fields"].push_back(bad["fields"][0]);
  refused(bad, "ascending");
  bad = config;
  bad["fields"][1] = config;
  refused(bad, "cannot be a BlockedField");
}

TEST_CASE("the blocks' models made one: the composite field, each cell's occupancy from its slab", "[blocks]") {
  std::vector<NerfModel> blocks(2);
  auto fields = TwoSlabs();
  for (int b = 0; b < 2; ++b) {
    blocks[b].field = MakeField<float>(fields->field(b).Config(), 0);
    CopyFieldParameters(fields->field(b), blocks[b].field.get());
    blocks[b].march_step = 0.01;
    blocks[b].background = {b == 0 ? 1.0f : 0.0f, 0.5f, 0.25f};
    std::vector<uint8_t> bits(8 * 8 * 8 / 8, b == 0 ? 0xff : 0x00);  // the first block's grid all occupied
    blocks[b].occupancy = OccupancyGrid(8, bits);
  }
  const NerfModel merged = MergeBlockModels(fields->slabs(), std::move(blocks));
  CHECK(merged.background == std::array<float, 3>{0.5f, 0.5f, 0.25f});
  CHECK(merged.field->Config() == fields->Config());
  for (const double x : {0.1, 0.3, 0.45, 0.6, 0.9}) {
    CHECK(merged.occupancy.Occupied(Eigen::Vector3d(x, 0.5, 0.5)) == (x < 0.4));
  }
  Matrix positions, directions, density, rgb, merged_density, merged_rgb;
  RandomSamples(32, &positions, &directions);
  fields->Render(positions, directions, &density, &rgb);
  merged.field->Render(positions, directions, &merged_density, &merged_rgb);
  CHECK(merged_density == density);
  CHECK(merged_rgb == rgb);

  std::vector<NerfModel> one(1);
  CHECK_THROWS_AS(MergeBlockModels(fields->slabs(), std::move(one)), std::invalid_argument);
  NgpFieldConfig other = SmallConfig();
  other.width = 32;
  NgpField<float> narrower(other, 1);
  CHECK_THROWS_AS(CopyFieldParameters(fields->field(0), &narrower), std::invalid_argument);
}

}  // namespace p2n::testing
