// Dotted-key options: registration from XxxOptions structs, typed parsing, config files, unknown keys.

#include <catch2/catch.hpp>

#include "base/errors.h"
#include "base/format.h"
#include "pipeline/options.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace {

struct ExampleOptions {
  static constexpr const char* kSection = "train";
  int steps = 100;  // an integer
  double learning_rate = 0.01;
  bool verbose = false;
  std::string mode = "fast";

  template <class V>
  void Visit(V& v) {
    v("steps", steps, "number of steps", "steps");
    v("learning_rate", learning_rate, "learning rate");
    v("verbose", verbose, "print more", "", OptionKind::kRuntime);
    v("mode", mode, "preset", "", OptionKind::kResult, {"fast", "slow"});
  }
  void Check() const { CheckField(*this, steps, steps > 0, "must be positive, not " + std::to_string(steps)); }
};

enum class Colour { kRed, kGreen, kBlue };

}  // namespace
}  // namespace p2n::testing

template <>
struct p2n::EnumNames<p2n::testing::Colour> {
  using Colour = p2n::testing::Colour;
  static constexpr std::pair<Colour, const char*> kValues[] = {
      {Colour::kRed, "red"}, {Colour::kGreen, "green"}, {Colour::kBlue, "blue"}};
};

namespace p2n::testing {
namespace {

// The typed kinds of option: a closed set, "auto or a number", a switch.
struct PaintOptions {
  static constexpr const char* kSection = "paint";
  Colour colour = Colour::kGreen;
  AutoOrNumber thinning;
  bool glossy = false;
  int coats = 2;

  template <class V>
  void Visit(V& v) {
    v("colour", colour, "the colour");
    v("thinning", thinning, "share of thinner; auto: by the colour");
    v("glossy", glossy, "a glossy finish");
    v("coats", coats, "coats of paint");
  }
  void Check() const {
    CheckField(*this, coats, coats >= 1 || colour != Colour::kRed,
               format("must be at least 1 when {} is {}", OptionKey(*this, colour), EnumName(colour)));
  }
};

OptionRegistry Registry() {
  OptionRegistry registry;
  RegisterOptions<ExampleOptions>(registry, "train");
  return registry;
}

}  // namespace

TEST_CASE("options come from the struct with its defaults and are read back", "[options]") {
  const OptionRegistry registry = Registry();
  REQUIRE(registry.specs().size() == 4);
  CHECK(registry.Find("train.steps")->default_value == 100);
  CHECK(registry.Find("train.steps")->unit == "steps");
  Config config(registry);
  config.SetFromText("train.steps", "5000", "--train.steps");
  config.SetFromText("train.learning_rate", "1e-3", "--train.learning_rate");
  config.SetFromText("train.verbose", "true", "--train.verbose");
  const ExampleOptions options = ReadOptions<ExampleOptions>(config, "train");
  CHECK(options.steps == 5000);
  CHECK(options.learning_rate == 1e-3);
  CHECK(options.verbose);
  // The key holds the result options set to other than their defaults: an option added later keeps old keys.
  CHECK(config.ResultOptions("train") == nlohmann::json{{"train.steps", 5000}, {"train.learning_rate", 1e-3}});
  config.SetFromText("train.mode", "fast", "--train.mode");
  config.SetFromText("train.learning_rate", "0.01", "--train.learning_rate");
  CHECK(config.ResultOptions("train") == nlohmann::json{{"train.steps", 5000}});
  CHECK(config.ExplicitResultOptions() ==
        nlohmann::json{{"train", {{"steps", 5000}, {"learning_rate", 0.01}, {"mode", "fast"}}}});
}

TEST_CASE("bad option values and unknown keys are user errors that name the key", "[options]") {
  const OptionRegistry registry = Registry();
  Config config(registry);
  CHECK_THROWS_WITH(config.SetFromText("train.step", "5", "--train.step"),
                    Catch::Contains("unknown option 'train.step'") && Catch::Contains("did you mean 'train.steps'?"));
  CHECK_THROWS_WITH(config.SetFromText("train.steps", "5.5", "--train.steps"),
                    Catch::Contains("'train.steps'") && Catch::Contains("must be an integer"));
  CHECK_THROWS_WITH(config.SetFromText("train.steps", "", "--train.steps"), Catch::Contains("must be an integer"));
  CHECK_THROWS_WITH(config.SetFromText("train.learning_rate", "nan", "x"), Catch::Contains("must be a number"));
  CHECK_THROWS_WITH(config.SetFromText("train.verbose", "maybe", "x"), Catch::Contains("true or false"));
  CHECK_THROWS_WITH(config.SetFromText("train.mode", "medium", "x"), Catch::Contains("one of: fast, slow"));
  CHECK_THROWS_WITH(config.Set("train.steps", "many", "x"), Catch::Contains("must be an integer"));
  config.Set("train.steps", 0, "x");
  CHECK_THROWS_WITH(ReadOptions<ExampleOptions>(config, "train"),
                    Catch::Equals("option train.steps must be positive, not 0"));
}

TEST_CASE("config files: nested or dotted keys, unknown keys rejected with their name and file", "[options]") {
  const OptionRegistry registry = Registry();
  TempDir dir;
  Config config(registry);
  WriteText(dir / "nested.json", R"({"train": {"steps": 7, "mode": "slow"}})");
  config.MergeFile(dir / "nested.json");
  CHECK(config.Get<int>("train.steps") == 7);
  CHECK(config.Get<std::string>("train.mode") == "slow");
  WriteText(dir / "flat.json", R"({"train.learning_rate": 2})");
  config.MergeFile(dir / "flat.json");
  CHECK(config.Get<double>("train.learning_rate") == 2.0);
  WriteText(dir / "unknown.json", R"({"train": {"stepz": 7}})");
  CHECK_THROWS_WITH(config.MergeFile(dir / "unknown.json"),
                    Catch::Contains("unknown option 'train.stepz'") && Catch::Contains("unknown.json"));
  WriteText(dir / "broken.json", R"({"train": )");
  CHECK_THROWS_WITH(config.MergeFile(dir / "broken.json"), Catch::Contains("broken.json' is not valid JSON"));
  CHECK_THROWS_WITH(config.MergeFile(dir / "missing.json"), Catch::Contains("cannot read config file"));
}

TEST_CASE("a merge that is told what to do with refused options sets the others", "[options]") {
  const OptionRegistry registry = Registry();
  Config config(registry);
  std::vector<std::string> refused;
  config.Merge(nlohmann::json{{"train", {{"stepz", 7}, {"steps", 9}, {"mode", "warp"}}}, {"train.learning_rate", 3}},
               "remembered.json", [&](const UserError& e) { refused.push_back(e.what()); });
  CHECK(config.Get<int>("train.steps") == 9);
  CHECK(config.Get<double>("train.learning_rate") == 3.0);
  CHECK(config.Get<std::string>("train.mode") == "fast");  // the default: "warp" refused
  REQUIRE(refused.size() == 2);
  CHECK_THAT(refused[0] + refused[1],
             Catch::Contains("'train.stepz'") && Catch::Contains("'warp'") && Catch::Contains("remembered.json"));
}

TEST_CASE("an auto-or-number option's text: auto, a whole number, or neither", "[options]") {
  std::optional<double> value = 3.0;
  CHECK(ParseAutoOrNumber("auto", &value));
  CHECK_FALSE(value);
  REQUIRE(ParseAutoOrNumber("-12.5", &value));
  CHECK(value == -12.5);
  CHECK(ParseAutoOrNumber("2e-3", &value));
  CHECK(*value == Approx(0.002));
  for (const char* bad : {"", "Auto", "10abc", "1e999", "nan", "inf", " "}) {
    INFO(bad);
    CHECK_FALSE(ParseAutoOrNumber(bad, &value));
    CHECK_FALSE(value);
  }
}

TEST_CASE("typed options: closed sets by their names, auto or a number, switches as on/off", "[options]") {
  OptionRegistry registry;
  RegisterOptions<PaintOptions>(registry, PaintOptions::kSection);
  CHECK(registry.Find("paint.colour")->default_value == "green");
  CHECK(registry.Find("paint.colour")->choices == std::vector<std::string>{"red", "green", "blue"});
  CHECK(registry.Find("paint.thinning")->default_value == "auto");
  CHECK(EnumNamesText<Colour>() == "red, green or blue");
  CHECK(EnumFromName<Colour>("blue") == Colour::kBlue);
  CHECK_FALSE(EnumFromName<Colour>("Blue"));

  Config config(registry);
  PaintOptions defaults = ReadOptions<PaintOptions>(config);
  CHECK(defaults.colour == Colour::kGreen);
  CHECK_FALSE(defaults.thinning.value);
  config.SetFromText("paint.colour", "red", "--paint.colour");
  config.SetFromText("paint.thinning", "0.25", "--paint.thinning");
  config.Merge(nlohmann::json{{"paint", {{"glossy", "on"}}}}, "paint.json");  // as a config file may say it
  const PaintOptions read = ReadOptions<PaintOptions>(config);
  CHECK(read.colour == Colour::kRed);
  CHECK(read.thinning.value == 0.25);
  CHECK(read.glossy);
  CHECK_THROWS_WITH(config.SetFromText("paint.colour", "purple", "x"), Catch::Contains("one of: red, green, blue"));
  CHECK_THROWS_WITH(config.Set("paint.glossy", "shiny", "x"), Catch::Contains("true or false"));
  config.SetFromText("paint.thinning", "some", "--paint.thinning");
  CHECK_THROWS_WITH(ReadOptions<PaintOptions>(config),
                    Catch::Equals("option paint.thinning must be auto or a number, not 'some'"));
}

TEST_CASE("Check() names an option's key from its declaration, never by spelling it", "[options]") {
  PaintOptions options;
  CHECK(OptionKey(options, options.thinning) == "paint.thinning");
  CHECK(OptionKey(&PaintOptions::coats) == "paint.coats");
  const int elsewhere = 0;
  CHECK_THROWS_AS(OptionKey(options, elsewhere), InternalError);
  options.coats = 0;
  CHECK_NOTHROW(options.Check());
  options.colour = Colour::kRed;
  CHECK_THROWS_WITH(options.Check(), Catch::Equals("option paint.coats must be at least 1 when paint.colour is red"));
}

}  // namespace p2n::testing
