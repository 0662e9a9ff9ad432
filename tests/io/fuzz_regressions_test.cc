// Every input a fuzzer ever found a bug with (tests/fixtures/fuzz/TARGET/),
// run through what the fuzzer feeds its reader (fuzz/fuzz_inputs.h): it
// must be read or refused with FileError, nothing else. docs/fuzzing.md.
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>

#include "tests/catch.h"

#include "fuzz/fuzz_inputs.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

TEST_CASE("inputs the fuzzers crashed on are read or refused with FileError", "[io][bad-input][fuzz]") {
  const std::map<std::string, std::function<void(std::string_view)>> targets = {
      {"graph", fuzz::Graph},         {"trajectory", fuzz::Trajectory}, {"scenario", fuzz::Scenario},
      {"dataset", fuzz::DatasetFolder}, {"import", fuzz::ImportRecording}, {"sweep", fuzz::Sweep},         {"vocabulary", fuzz::VocabularyFile},
      {"image", fuzz::Image}};
  const std::filesystem::path root = testing::Fixture("fuzz");
  int inputs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(root)) {
    const std::string target = entry.path().filename().string();
    INFO("target " << target);
    REQUIRE(targets.count(target) == 1);  // a folder per fuzz target
    for (const auto& file : std::filesystem::directory_iterator(entry.path())) {
      std::ifstream in(file.path(), std::ios::binary);
      std::ostringstream bytes;
      bytes << in.rdbuf();
      const std::string input = bytes.str();
      INFO("input " << file.path());
      CHECK_NOTHROW(targets.at(target)(input));
      ++inputs;
    }
  }
  CHECK(inputs >= 2);
  std::filesystem::remove_all(fuzz::ScratchDir());
}

}  // namespace
}  // namespace catgraph
