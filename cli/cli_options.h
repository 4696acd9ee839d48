#pragma once
// What the pipeline subcommands share: the workspace flag, dotted option flags generated from the option
// registry, config resolution, and runtime settings (threads, logging, progress).

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "pipeline/options.h"
#include "pipeline/workspace.h"

namespace p2n {

// The flags of one pipeline subcommand as typed.
struct CommonFlags {
  std::string workspace;
  std::string config_file;
  std::map<std::string, std::string> option_text;  // dotted key -> text, for the --section.key flags given
};

// Adds one --section.key flag for every registered option (with its help, type, unit and default) to `app`;
// the text of each flag given lands in `option_text`.
void AddOptionFlags(CLI::App& app, const OptionRegistry& registry, std::map<std::string, std::string>* option_text);
// Adds -w/--workspace, --config, --colmap (an alias of --sfm.colmap) and the option flags.
void AddCommonFlags(CLI::App& app, const OptionRegistry& registry, CommonFlags* flags);

// Parses argv into `app`. Returns an exit code when the process should end now (--help: 0); throws UserError
// for a malformed command line, naming the unknown option and the nearest known one.
std::optional<int> Parse(CLI::App& app, const OptionRegistry& registry, int argc, char** argv);

// The resolved configuration: defaults, then what the workspace remembers (options.json; a value another version
// remembered that this one does not take, or whose rule it breaks, is left out with a warning), then --config, then
// the flags; every value checked, an error naming where a refused one came from. With `remember`, writes options.json
// (the result options set so far) and config.json (everything) into the workspace.
Config ResolveConfig(const OptionRegistry& registry, const Workspace& workspace, const CommonFlags& flags,
                     bool remember);

// The options the workspace remembers (options.json) that this version takes, as "key value" pairs joined by ", ";
// "" when none.
std::string RememberedOptionsText(const OptionRegistry& registry, const Workspace& workspace);

// Applies run.threads, run.log_level and run.progress and sends the log also to `log_file`. The returned
// object keeps the thread limit alive.
std::unique_ptr<tbb::global_control> ApplyRunOptions(const Config& config, const std::filesystem::path& log_file);

}  // namespace p2n
