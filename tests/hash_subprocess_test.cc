// Stable hashes, atomic writes and the subprocess helper.

#include <catch2/catch.hpp>

#include <chrono>
#include <future>
#include <thread>

#include "base/errors.h"
#include "base/file_util.h"
#include "pipeline/cancel.h"
#include "pipeline/hash.h"
#include "pipeline/subprocess.h"
#include "tests/test_util.h"

namespace p2n::testing {

TEST_CASE("SHA-1 is the standard one, for strings and files", "[hash]") {
  // FIPS 180 test vector.
  CHECK(Catch::toLower(Sha1Hex("abc")) == "a9993e364706816aba3e25717850c26c9cd0d89d");
  TempDir dir;
  WriteText(dir / "f.txt", "abc");
  CHECK(Sha1OfFile(dir / "f.txt") == Sha1Hex("abc"));
  CHECK_THROWS_WITH(Sha1OfFile(dir / "missing"), Catch::Contains("missing"));
  // Fields are framed: moving a byte between fields changes the digest.
  CHECK(Hasher().Field("ab").Field("c").HexDigest() != Hasher().Field("a").Field("bc").HexDigest());
}

TEST_CASE("atomic writes leave the old file or the new one, and name the file on failure", "[files]") {
  TempDir dir;
  WriteFileAtomic(dir / "a.json", "one");
  WriteFileAtomic(dir / "a.json", "two");
  CHECK(ReadText(dir / "a.json") == "two");
  CHECK_FALSE(std::filesystem::exists(dir / "a.json.tmp"));
  CHECK_THROWS_WITH(WriteFileAtomic(dir / "no_such_folder" / "a.json", "x"), Catch::Contains("no_such_folder/a.json"));
}

TEST_CASE("subprocess: argv, log file, exit status", "[subprocess]") {
  TempDir dir;
  const auto log = dir / "logs" / "step.log";
  SubprocessResult result =
      RunSubprocess({"sh", "-c", "echo hello; echo oops >&2; exit 3", "name with space"}, log, "test step");
  CHECK(result.exit_code == 3);
  const std::string text = ReadText(log);
  CHECK_THAT(text, Catch::Contains("$ sh -c 'echo hello; echo oops >&2; exit 3' 'name with space'"));
  CHECK_THAT(text, Catch::Contains("hello") && Catch::Contains("oops"));
  CHECK_THROWS_WITH(CheckSubprocess({"false"}, log, "the false step"),
                    Catch::Contains("the false step failed with exit code 1") && Catch::Contains(log.string()));
  CHECK_THROWS_AS(RunSubprocess({"photo2nerf-no-such-program"}, log, "missing"), ExternalToolError);
  CHECK_THROWS_WITH(CheckSubprocess({"sh", "-c", "kill -9 $$"}, log, "killed step"), Catch::Contains("signal 9"));
  // Arguments are passed as they are, never through a shell.
  RunSubprocess({"echo", "$HOME;", "`id`"}, log, "echo");
  CHECK_THAT(ReadText(log), Catch::Contains("$HOME; `id`"));
}

TEST_CASE("subprocess: cancellation stops the child and throws Cancelled", "[subprocess]") {
  TempDir dir;
  ResetCancel();
  const auto start = std::chrono::steady_clock::now();
  auto future = std::async(std::launch::async, [&] { RunSubprocess({"sleep", "30"}, dir / "log", "sleeping"); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  RequestCancel();
  CHECK_THROWS_AS(future.get(), Cancelled);
  ResetCancel();
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(10));
}

}  // namespace p2n::testing
