// The engine's option structs: Check() names the field and its rule; configs round-trip exactly through JSON and
// refuse keys they do not read (issue 18).

#include <catch2/catch.hpp>

#include <cstdint>
#include <limits>

#include "base/json_number.h"
#include "mesh/mesh.h"
#include "nerf/adam.h"
#include "nerf/encoding.h"
#include "nerf/make_field.h"
#include "nerf/ngp_field.h"
#include "nerf/radiance_field.h"
#include "nerf/renderer.h"
#include "nerf/trainer.h"
#include "nerf/vanilla_field.h"

namespace p2n::testing {

TEST_CASE("engine option checks name the field, the rule and the value", "[config]") {
  TrainerOptions trainer;
  CHECK_NOTHROW(trainer.Check());
  trainer.distortion_weight = -0.5;
  CHECK_THROWS_WITH(trainer.Check(), "trainer.distortion_weight must be at least 0, not -0.5");
  trainer = TrainerOptions{};
  trainer.min_batch_rays = trainer.max_batch_rays + 1;
  CHECK_THROWS_WITH(trainer.Check(), Catch::StartsWith("trainer.min_batch_rays must be 1..max_batch_rays"));
  trainer = TrainerOptions{};
  trainer.occupancy_decay = 0;
  CHECK_THROWS_WITH(trainer.Check(), "trainer.occupancy_decay must be in (0, 1], not 0");

  HashGridConfig grid;
  CHECK_NOTHROW(grid.Check());
  grid.levels = 0;
  CHECK_THROWS_WITH(grid.Check(), "hash_grid.levels must be 1..64, not 0");
  grid = HashGridConfig{};
  grid.finest_resolution = grid.base_resolution - 1;
  CHECK_THROWS_WITH(HashGridEncoding<float>(3, grid, 1), Catch::StartsWith("hash_grid.finest_resolution must be"));

  AdamOptions adam;
  adam.beta2 = 1;
  CHECK_THROWS_WITH(adam.Check(), "adam.beta2 must be in [0, 1), not 1");
  RenderOptions render;
  render.max_samples = 0;
  CHECK_THROWS_WITH(render.Check(), "render.max_samples must be at least 1, not 0");
  MeshOptions mesh;
  mesh.resolution = 4;
  CHECK_THROWS_WITH(mesh.Check(), "mesh.resolution must be 8..1024, not 4");
}

TEST_CASE("every field type's config round-trips exactly through JSON and the field", "[config]") {
  // Every field away from its default.
  const NgpFieldConfig ngp{.grid = {8, 4, 15, 12, 1000},
                           .planes = std::nullopt,
                           .geometry_features = 7,
                           .width = 32,
                           .density_hidden_layers = 2,
                           .colour_hidden_layers = 1};
  const VanillaFieldConfig vanilla{
      .position_levels = 6, .direction_levels = 2, .width = 48, .layers = 4, .colour_width = 24};
  CHECK(NgpFieldConfig::FromJson(ngp.ToJson()) == ngp);
  CHECK(VanillaFieldConfig::FromJson(vanilla.ToJson()) == vanilla);
  CHECK(HashGridConfig::FromJson(ngp.grid.ToJson()) == ngp.grid);
  // The registry of field types (MakeField) gives back the config it was made from, key for key.
  for (const nlohmann::json& config : {ngp.ToJson(), vanilla.ToJson()}) {
    INFO(config.dump());
    CHECK(MakeField<float>(config, 1)->Config() == config);
    CHECK(MakeField<double>(config, 1)->Config() == config);
  }
}

TEST_CASE("a config with an unknown key or a derived key that does not follow is refused", "[config][bad_input]") {
  nlohmann::json grid = HashGridConfig{}.ToJson();
  grid["levles"] = 4;
  CHECK_THROWS_WITH(HashGridConfig::FromJson(grid), "hash grid config: unknown key 'levles'");
  nlohmann::json ngp = NgpFieldConfig{}.ToJson();
  ngp["density_activation"] = "softplus";
  CHECK_THROWS_WITH(NgpFieldConfig::FromJson(ngp),
                    Catch::Contains("'density_activation' follows from the other fields"));
  ngp = NgpFieldConfig{}.ToJson();
  ngp["widht"] = 128;
  CHECK_THROWS_WITH(MakeField<float>(ngp, 1), "NgpField config: unknown key 'widht'");
  nlohmann::json vanilla = VanillaFieldConfig{}.ToJson();
  vanilla["skip_after"] = 1;
  CHECK_THROWS_WITH(VanillaFieldConfig::FromJson(vanilla),
                    Catch::Contains("'skip_after' follows from the other fields"));
  CHECK_THROWS_WITH(NgpFieldConfig::FromJson({{"width", "wide"}}),
                    "NgpField config: 'width' must be an integer, not \"wide\"");
  CHECK_THROWS_WITH(NgpFieldConfig::FromJson({{"width", int64_t{1} << 40}}),
                    "NgpField config: 'width' must be an integer, not 1099511627776");
  // What a config leaves out keeps its default.
  CHECK(NgpFieldConfig::FromJson({{"otype", "NgpField"}, {"width", 32}}).grid == HashGridConfig{});
}

TEST_CASE("JsonInteger returns only integers the type holds", "[config][bad_input]") {
  using nlohmann::json;
  CHECK(JsonInteger<int>(json(7)) == 7);
  CHECK(JsonInteger<int>(json(-7)) == -7);
  CHECK(JsonInteger<int>(json(int64_t{std::numeric_limits<int>::max()})) == std::numeric_limits<int>::max());
  CHECK_FALSE(JsonInteger<int>(json(int64_t{std::numeric_limits<int>::max()} + 1)));
  CHECK_FALSE(JsonInteger<int>(json(int64_t{std::numeric_limits<int>::min()} - 1)));
  CHECK_FALSE(JsonInteger<uint64_t>(json(-1)));
  CHECK(JsonInteger<uint64_t>(json(std::numeric_limits<uint64_t>::max())) == std::numeric_limits<uint64_t>::max());
  CHECK_FALSE(JsonInteger<int64_t>(json(std::numeric_limits<uint64_t>::max())));
  CHECK_FALSE(JsonInteger<int>(json(2.0)));
  CHECK_FALSE(JsonInteger<int>(json(1e30)));
  CHECK_FALSE(JsonInteger<int>(json("2")));
  CHECK_FALSE(JsonInteger<int>(json()));
}

}  // namespace p2n::testing
