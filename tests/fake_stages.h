#pragma once
// Small stages for testing the pipeline: each counts its runs in a file, writes out.txt from its option and
// its upstream's out.txt, and can be told to fail or to block (so that a test can kill it mid-run).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "pipeline/options.h"
#include "pipeline/runner.h"

namespace p2n::testing {

struct FakeOptions {
  int value = 1;              // written into out.txt: changes the result
  bool fail = false;          // throw a UserError in the middle of Run()
  bool block = false;         // write started.flag into the counter folder, then sleep for a minute
  int min_value = 0;          // a threshold: a result whose value is below it fails (Run and CheckResult)
  bool read_upstream = true;  // false: the stage reads no upstream stage (Stage::UpstreamFor)
  int noise = 0;              // written into noise.txt when not 0: a result that the key does not determine

  template <class V>
  void Visit(V& v) {
    v("value", value, "the value written into out.txt");
    v("fail", fail, "fail in the middle of the run", "", OptionKind::kRuntime);
    v("block", block, "block in the middle of the run", "", OptionKind::kRuntime);
    v("min_value", min_value, "the least value a result may have", "", OptionKind::kCheck);
    v("read_upstream", read_upstream, "read the upstream stage's result");
    v("noise", noise, "written into noise.txt (as a time budget's result differs)", "", OptionKind::kRuntime);
  }
  void Check() const {}
};

// Three stages a -> b -> c; the registry holds a.*, b.*, c.* and run.threads (kRuntime). Stage "a" has one
// external input: the file `counter_dir/input.txt` (labelled "file input.txt") when it exists (a UserError
// when it is not a regular file). Stage b's
// format version is read from `counter_dir/b.version` (default 1), a stand-in for a code change.
OptionRegistry FakeOptionsRegistry();
Runner MakeFakeRunner(const std::filesystem::path& counter_dir);
int RunCount(const std::filesystem::path& counter_dir, const std::string& stage);

}  // namespace p2n::testing
