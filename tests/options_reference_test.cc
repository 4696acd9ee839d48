// docs/options.md is what the declared options make, so the reference cannot drift from the code.

#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "pipeline/options_reference.h"
#include "stages/stages.h"

namespace p2n {
namespace {

TEST_CASE("docs/options.md is the reference the declared options make", "[options]") {
  const std::string reference = OptionsReference(AllOptions());
  std::ifstream file(std::string(P2N_SOURCE_DIR) + "/docs/options.md", std::ios::binary);
  REQUIRE(file.good());
  std::ostringstream text;
  text << file.rdbuf();
  INFO("docs/options.md is out of date: remake it with `build/cli/photo2nerf options > docs/options.md`");
  CHECK(text.str() == reference);
}

TEST_CASE("The options reference has a row for every option, its default and kind", "[options]") {
  const OptionRegistry registry = AllOptions();
  const std::string reference = OptionsReference(registry);
  for (const OptionSpec& spec : registry.specs()) {
    INFO(spec.key);
    CHECK(reference.find("| `" + spec.key + "` |") != std::string::npos);
  }
  CHECK(reference.find("| `train.preset` | `default` |  | result |") != std::string::npos);
  CHECK(reference.find("| `run.threads` |") != std::string::npos);
  CHECK(reference.find("\n## sfm\n") != std::string::npos);
}

}  // namespace
}  // namespace p2n
