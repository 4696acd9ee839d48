#include "pipeline/options_reference.h"

#include "base/format.h"

namespace p2n {
namespace {

constexpr const char* kIntroduction = R"(# Options

Made by `photo2nerf options` from the options as the code declares them; a test fails when this file is out of
date, and `build/cli/photo2nerf options > docs/options.md` remakes it.

Give an option as `--section.key VALUE`, or in a JSON file with `--config FILE` (nested, `{"train": {"steps":
500}}`, or flat, `{"train.steps": 500}`). An unknown key is an error that names the nearest known one.

Kinds: a *result* option changes what its stage makes; the workspace remembers it (`options.json`) and the stage's
cache key holds it when it is not at its default. A *check* option is a pass/fail threshold on a result: remembered,
in no key. A *runtime* option (threads, logging, checkpoints, the scheduler) changes no result and is not
remembered. Where a default is `auto`, the option's text says what auto chooses.
)";

// A value or text inside a table cell: pipes escaped.
std::string Cell(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string DefaultText(const nlohmann::json& value) {
  const std::string text = value.is_string() ? value.get<std::string>() : value.dump();
  return text.empty() ? "(empty)" : "`" + Cell(text) + "`";
}

std::string Row(const OptionSpec& spec) {
  std::string what = spec.help;
  if (!spec.choices.empty()) {
    std::string names;
    for (const std::string& choice : spec.choices) names += (names.empty() ? "`" : ", `") + choice + "`";
    what += " (one of " + names + ")";
  }
  return format("| `{}` | {} | {} | {} | {} |\n", spec.key, DefaultText(spec.default_value),
                spec.unit.empty() ? "" : Cell(spec.unit), EnumName(spec.kind), Cell(what));
}

}  // namespace

std::string OptionsReference(const OptionRegistry& registry) {
  std::string text = kIntroduction;
  std::string section;
  for (const OptionSpec& spec : registry.specs()) {
    const std::string its_section = spec.key.substr(0, spec.key.find('.'));
    if (its_section != section) {
      section = its_section;
      text += format("\n## {}\n\n| option | default | unit | kind | what it does |\n| --- | --- | --- | --- | --- |\n",
                     section);
    }
    text += Row(spec);
  }
  return text;
}

}  // namespace p2n
