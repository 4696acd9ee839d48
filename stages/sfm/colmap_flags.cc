#include "stages/sfm/colmap_flags.h"

#include <map>
#include <mutex>
#include <regex>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "pipeline/subprocess.h"

namespace p2n {

ColmapVersion ParseColmapVersion(std::string_view banner) {
  static const std::regex kVersion(R"(COLMAP\s+(\d+)\.(\d+))");
  std::match_results<std::string_view::const_iterator> match;
  if (!std::regex_search(banner.begin(), banner.end(), match, kVersion)) {
    const std::string start(banner.substr(0, 200));
    throw UserError(format("cannot tell the COLMAP version from its output: '{}'; is this COLMAP?", start));
  }
  return {std::stoi(match[1].str()), std::stoi(match[2].str())};
}

ColmapVersion DetectColmapVersion(const std::string& program, const std::filesystem::path& log_file) {
  // Asked once per program and process: status and run both need it.
  static std::mutex mutex;
  static std::map<std::string, ColmapVersion> known;
  std::lock_guard lock(mutex);
  if (const auto it = known.find(program); it != known.end()) return it->second;
  // `colmap help` exits 0 on 3.x; its banner is the first line.
  const SubprocessResult result = RunSubprocess({program, "help"}, log_file, "reading the COLMAP version");
  const std::string text = ReadTextFile(log_file);
  if (result.signal != 0 || text.find("COLMAP") == std::string::npos) {
    throw ExternalToolError(format("'{} help' did not print COLMAP's banner (exit {}, signal {}); log: {}", program,
                                   result.exit_code, result.signal, log_file.string()));
  }
  return known[program] = ParseColmapVersion(text);
}

ColmapFlags ColmapFlagsFor(const ColmapVersion& version) {
  const bool feature = version.AtLeast(3, 13);
  const std::string extraction = feature ? "--FeatureExtraction." : "--SiftExtraction.";
  const std::string matching = feature ? "--FeatureMatching." : "--SiftMatching.";
  return {extraction + "use_gpu",        extraction + "num_threads",
          extraction + "max_image_size", "--SiftExtraction.max_num_features",
          matching + "use_gpu",          matching + "num_threads"};
}

}  // namespace p2n
