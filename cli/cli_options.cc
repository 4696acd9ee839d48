#include "cli/cli_options.h"

#include <tbb/global_control.h>

#include <filesystem>
#include <functional>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/sfm/sfm_options.h"
#include "stages/stages.h"

namespace p2n {
namespace fs = std::filesystem;

void AddCommonFlags(CLI::App& app, const OptionRegistry& registry, CommonFlags* flags) {
  app.add_option("-w,--workspace", flags->workspace, "workspace folder (results, logs, cache)")->required();
  app.add_option("--config", flags->config_file, "JSON file of options, nested or as dotted keys");
  app.add_option_function<std::string>(
      "--colmap", [flags](const std::string& program) { flags->option_text[OptionKey(&SfmOptions::colmap)] = program; },
      format("the COLMAP program, when it is not `colmap` on PATH (same as --{})", OptionKey(&SfmOptions::colmap)));
  AddOptionFlags(app, registry, &flags->option_text);
}

void AddOptionFlags(CLI::App& app, const OptionRegistry& registry, std::map<std::string, std::string>* option_text) {
  for (const OptionSpec& spec : registry.specs()) {
    std::string help = spec.help;
    if (!spec.unit.empty()) help += " [" + spec.unit + "]";
    std::string type = spec.default_value.is_boolean()          ? "BOOL"
                       : spec.default_value.is_number_integer() ? "INT"
                       : spec.default_value.is_number()         ? "NUMBER"
                                                                : "TEXT";
    if (!spec.choices.empty()) {
      type.clear();
      for (const std::string& choice : spec.choices) type += (type.empty() ? "" : "|") + choice;
    }
    const std::string default_text =
        spec.default_value.is_string() ? spec.default_value.get<std::string>() : spec.default_value.dump();
    app.add_option_function<std::string>(
           "--" + spec.key, [option_text, key = spec.key](const std::string& text) { (*option_text)[key] = text; },
           help)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast)  // the last value given wins
        ->type_name(type)
        ->default_str(default_text)
        ->group(spec.kind == OptionKind::kResult  ? "Options that change results (remembered by the workspace)"
                : spec.kind == OptionKind::kCheck ? "Checks on results (remembered, not in any cache key)"
                                                  : "Runtime options (not remembered, not in any cache key)");
  }
}

std::optional<int> Parse(CLI::App& app, const OptionRegistry& registry, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ExtrasError&) {
    std::string message;
    for (const std::string& extra : app.remaining()) {
      if (extra.rfind("--", 0) != 0) {
        message = format("unexpected argument '{}'", extra);
        break;
      }
      const std::string key =
          extra.substr(2, extra.find('=') == std::string::npos ? std::string::npos : extra.find('=') - 2);
      message = format("unknown option '--{}'", key);
      const std::string suggestion = registry.Suggest(key);
      if (!suggestion.empty()) message += format("; did you mean '--{}'?", suggestion);
      break;
    }
    throw UserError(format("{} (see `{} --help`)", message, app.get_name()));
  } catch (const CLI::ParseError& e) {
    throw UserError(format("{} (see `{} --help`)", e.what(), app.get_name()));
  }
  return std::nullopt;
}

namespace {

using Refused = std::function<void(const UserError&)>;

// A rule's refusal of a value, saying where the value came from.
UserError FromOrigin(const OptionError& e, const std::string& origin) {
  return UserError(format("option {} (from {}) {}", e.key(), origin, e.rule()));
}

// What the workspace remembers (options.json), as this version reads it: a value it does not take (an option since
// removed, a choice no longer offered, a rule since changed) is left out and passed to `refused`.
Config ReadRemembered(const OptionRegistry& registry, const fs::path& file, const Refused& refused) {
  Config config(registry);
  if (!fs::exists(file)) return config;
  config.Merge(ReadJsonFile(file), file.string(), refused);
  while (true) {
    try {
      CheckAllOptions(config);
      return config;
    } catch (const OptionError& e) {
      if (config.Origin(e.key()).empty()) return config;  // a rule between options: checked once all are in
      refused(FromOrigin(e, file.string()));
      config.Unset(e.key());
    }
  }
}

}  // namespace

Config ResolveConfig(const OptionRegistry& registry, const Workspace& workspace, const CommonFlags& flags,
                     bool remember) {
  const fs::path remembered = workspace.RememberedOptionsPath();
  Config config = ReadRemembered(registry, remembered, [](const UserError& e) {
    LogWarning(format("{}: left out, as this version of photo2nerf does not take it", e.what()));
  });
  if (!flags.config_file.empty()) config.MergeFile(flags.config_file);
  for (const auto& [key, text] : flags.option_text) config.SetFromText(key, text, "--" + key);
  try {
    CheckAllOptions(config);
  } catch (const OptionError& e) {
    const std::string origin = config.Origin(e.key());
    if (origin.empty()) throw;
    throw FromOrigin(e, origin);
  }
  if (!remember) return config;
  WriteJsonAtomic(remembered, config.ExplicitResultOptions());
  WriteJsonAtomic(workspace.ConfigPath(), config.ToJson());
  return config;
}

std::string RememberedOptionsText(const OptionRegistry& registry, const Workspace& workspace) {
  const Config config =
      ReadRemembered(registry, workspace.RememberedOptionsPath(), [](const UserError&) {});  // ResolveConfig warns
  const nlohmann::json options = config.ExplicitResultOptions();
  std::string text;
  for (const auto& [section, values] : options.items()) {
    for (const auto& [name, value] : values.items()) {
      text += format("{}{}.{} {}", text.empty() ? "" : ", ", section, name,
                     value.is_string() ? value.get<std::string>() : value.dump());
    }
  }
  return text;
}

std::unique_ptr<tbb::global_control> ApplyRunOptions(const Config& config, const fs::path& log_file) {
  const RunOptions options = ReadOptions<RunOptions>(config);
  SetLogLevel(options.log_level);
  SetProgressStyle(options.progress);
  SetLogFile(log_file);
  if (options.threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<size_t>(options.threads));
}

}  // namespace p2n
