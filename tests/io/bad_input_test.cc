// Every kind of bad input gives one FileError naming the file, the line and
// what was expected.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/catch.h"

#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

constexpr const char* kGood = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
constexpr const char* kInfo = " 1 0 0 1 0 1";

// Reads `text` as file "bad.g2o" and returns the error message; fails the
// test if no FileError is thrown.
std::string GraphReadError(const std::string& text, const std::string& name = "bad.g2o") {
  std::istringstream in(text);
  try {
    ReadGraph(in, name);
  } catch (const FileError& e) {
    return e.what();
  }
  FAIL("no FileError for input:\n" << text);
  return {};
}

void CheckError(const std::string& text, const std::string& where, const std::string& what) {
  const std::string message = GraphReadError(text);
  INFO(message);
  CHECK(message.rfind(where, 0) == 0);  // starts with file:line
  CHECK(message.find(what) != std::string::npos);
  CHECK(message.find('\n') == std::string::npos);  // one line
}

TEST_CASE("an unknown tag names the tag and the expected ones", "[io][bad-input]") {
  CheckError(std::string(kGood) + "EDGE_SE2_FOO 0 1 1 0 0" + kInfo + "\n", "bad.g2o:3:",
             "unknown tag 'EDGE_SE2_FOO'");
  CheckError("HELLO world\n", "bad.g2o:1:", "unknown tag 'HELLO'");
}

TEST_CASE("a truncated line says how many values were expected", "[io][bad-input]") {
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 1 0 0 1 0 0\n", "bad.g2o:3:",
             "expected 11 values");
  CheckError("VERTEX_SE3:QUAT 0 0 0 0 0 0\n", "bad.g2o:1:", "expected 8 values");
}

TEST_CASE("a non-number is reported with the field it was meant for", "[io][bad-input]") {
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 1 zero 0" + kInfo + "\n", "bad.g2o:3:",
             "expected a number for y, found 'zero'");
  CheckError("VERTEX_SE2 a 0 0 0\n", "bad.g2o:1:", "integer id");
  CheckError("VERTEX_SE2 -3 0 0 0\n", "bad.g2o:1:", "non-negative integer id");
  CheckError("VERTEX_SE2 99999999999999999999 0 0 0\n", "bad.g2o:1:", "integer id");
}

TEST_CASE("NaN and infinity are rejected", "[io][bad-input]") {
  CheckError("VERTEX_SE2 0 nan 0 0\n", "bad.g2o:1:", "finite number");
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 inf 0 0" + kInfo + "\n", "bad.g2o:3:",
             "finite number");
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 -inf\n", "bad.g2o:3:",
             "finite number");
}

TEST_CASE("a non-positive-definite information matrix is rejected", "[io][bad-input]") {
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 0\n", "bad.g2o:3:",
             "not positive definite");
  CheckError(std::string(kGood) + "EDGE_SE2 0 1 1 0 0 1 2 0 1 0 1\n", "bad.g2o:3:",
             "not positive definite");
}

TEST_CASE("an edge to a missing vertex names the vertex", "[io][bad-input]") {
  CheckError(std::string(kGood) + "EDGE_SE2 0 5 1 0 0" + kInfo + "\n", "bad.g2o:3:",
             "vertex 5, which is not defined");
  CheckError(std::string(kGood) + "EDGE_SE2_SWITCHABLE 0 1 9 1 0 0" + kInfo + "\n",
             "bad.g2o:3:", "switch 9");
  CheckError(std::string(kGood) + "FIX 7\n", "bad.g2o:3:", "FIX refers to vertex 7");
  CheckError(std::string(kGood) + "EDGE_SE2 7 7 1 0 0" + kInfo + "\n", "bad.g2o:3:",
             "vertex 7, which is not defined");
}

TEST_CASE("a duplicate vertex id names both lines", "[io][bad-input]") {
  CheckError(std::string(kGood) + "VERTEX_SE2 1 5 5 0\n", "bad.g2o:3:",
             "duplicate vertex id 1 (pose); it was first defined on line 2");
  CheckError(std::string(kGood) + "VERTEX_SWITCH 1 1\n", "bad.g2o:3:", "duplicate vertex id 1");
}

TEST_CASE("mixing 2D and 3D tags is rejected", "[io][bad-input]") {
  CheckError(std::string(kGood) + "VERTEX_SE3:QUAT 2 0 0 0 0 0 0 1\n", "bad.g2o:3:",
             "one dimension per file");
}

TEST_CASE("an empty file or one with only comments is rejected", "[io][bad-input]") {
  CheckError("", "bad.g2o:1:", "empty");
  CheckError("# nothing here\n\n", "bad.g2o:2:", "no vertex or edge");
  CheckError("VERTEX_SWITCH 0 1\n", "bad.g2o:1:", "no vertex or edge");
}

TEST_CASE("a hostile line length is rejected before it is read whole", "[io][bad-input]") {
  CheckError("VERTEX_SE2 0 0 0 0\n" + std::string(1 << 20, '1') + "\n", "bad.g2o:2:",
             "line longer than");
}

TEST_CASE("malformed closure metadata is reported", "[io][bad-input]") {
  CheckError(std::string(kGood) + "#CATGRAPH_CLOSURE 3 nonsense\nEDGE_SE2 0 1 1 0 0" + kInfo +
                 "\n",
             "bad.g2o:3:", "expected '<closure-id> <kind>");
  CheckError(std::string(kGood) + "#CATGRAPH_CLOSURE 3 visual\n", "bad.g2o:3:",
             "at the end of the file");
}

TEST_CASE("a forced format rejects another format's tags", "[io][bad-input]") {
  std::istringstream in("VERTEX_SE2 0 0 0 0\n");
  ReadGraphOptions options;
  options.format = GraphFormat::kToro;
  try {
    ReadGraph(in, "x.graph", options);
    FAIL("expected a FileError");
  } catch (const FileError& e) {
    CHECK(std::string(e.what()).find("x.graph:1: unknown tag 'VERTEX_SE2' for the toro format") ==
          0);
  }
}

TEST_CASE("a missing file and a directory give a one-line error without a line number",
          "[io][bad-input]") {
  const auto dir = std::filesystem::temp_directory_path();
  try {
    ReadGraphFile(dir / "catgraph_no_such_file.g2o");
    FAIL("expected a FileError");
  } catch (const FileError& e) {
    CHECK(std::string(e.what()).find("no such file") != std::string::npos);
    CHECK(e.line() == 0);
  }
  try {
    ReadGraphFile(dir);
    FAIL("expected a FileError");
  } catch (const FileError& e) {
    CHECK(std::string(e.what()).find("is a directory") != std::string::npos);
  }
}

TEST_CASE("a quaternion whose norm overflows is refused, not normalised to NaN", "[io][bad-input]") {
  CheckError("VERTEX_SE3:QUAT 0 0 0 0 1e300 1e300 0 1\n", "bad.g2o:1:",
             "VERTEX_SE3:QUAT: the quaternion's norm overflows");
}

TEST_CASE("a FIFO is refused at once, not waited on", "[io][bad-input]") {
  const auto dir = testing::TempDir("bad_input_fifo");
  const std::filesystem::path fifo = dir / "graph.g2o";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  try {
    ReadGraphFile(fifo);  // would block forever in open(2) without a writer
    FAIL("expected a FileError");
  } catch (const FileError& e) {
    CHECK(std::string(e.what()) == fifo.string() + ": is not a regular file (a FIFO, device or socket); expected a "
                                                   "pose-graph file (g2o, TORO or iSAM)");
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("control bytes of the input are escaped: the message stays one harmless line", "[io][bad-input]") {
  const std::string message = GraphReadError("VERTEX_SE2 0 0 0 0\nVERTEX_\x1b[31mX\x07 1 0 0 0\n");
  INFO(message);
  CHECK(message.find('\x1b') == std::string::npos);
  CHECK(message.find('\x07') == std::string::npos);
  CHECK(message.find("VERTEX_\\x1b[31mX\\x07") != std::string::npos);
  CHECK(FileError("a\nb", 2, "c\rd").what() == std::string("a\\x0ab:2: c\\x0dd"));
}

}  // namespace
}  // namespace catgraph
