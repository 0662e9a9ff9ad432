// Tokenised text lines with checked accessors, shared by catgraph's readers.
#ifndef CATGRAPH_BACKEND_IO_INTERNAL_TEXT_LINE_H_
#define CATGRAPH_BACKEND_IO_INTERNAL_TEXT_LINE_H_

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <istream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/ids.h"
#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"
#include "backend/io/file_error.h"

namespace catgraph {

inline constexpr std::string_view kWhitespace = " \t\r\v\f";

inline std::vector<std::string_view> Tokenize(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t pos = 0;
  while (true) {
    pos = line.find_first_not_of(kWhitespace, pos);
    if (pos == std::string_view::npos) break;
    const std::size_t end = std::min(line.find_first_of(kWhitespace, pos), line.size());
    tokens.push_back(line.substr(pos, end - pos));
    pos = end;
  }
  return tokens;
}

// The comma-separated fields of one CSV line, each without surrounding
// whitespace (no quoting: catgraph's CSV files hold numbers and names).
inline std::vector<std::string_view> SplitCsv(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::string_view field = line.substr(start, comma == std::string_view::npos ? line.npos : comma - start);
    const std::size_t b = field.find_first_not_of(kWhitespace);
    const std::size_t e = field.find_last_not_of(kWhitespace);
    fields.push_back(b == std::string_view::npos ? std::string_view() : field.substr(b, e - b + 1));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

// One tokenised line with checked accessors that throw FileError.
class Line {
 public:
  // `context` prefixes the messages about values; empty = the first token
  // (the tag of a graph line).
  Line(const std::string& file, int number, std::vector<std::string_view> tokens,
       std::string_view context = {})
      : file_(file), number_(number), tokens_(std::move(tokens)), context_(context) {}

  int number() const { return number_; }
  std::size_t size() const { return tokens_.size(); }
  std::string_view tag() const { return tokens_.front(); }
  std::string_view token(std::size_t index) const { return tokens_.at(index); }
  std::string context() const { return std::string(context_.empty() ? tag() : context_); }

  [[noreturn]] void Fail(const std::string& message) const {
    throw FileError(file_, number_, message);
  }
  void ExpectValues(std::size_t count, std::string_view layout) const {
    const std::size_t found = tokens_.size() - 1;
    if (found != count) {
      Fail(context() + ": expected " + std::to_string(count) + " values (" +
           std::string(layout) + "), found " + std::to_string(found) +
           (found < count ? " (truncated line?)" : ""));
    }
  }
  double Number(std::size_t index, std::string_view what) const {
    const std::string_view token = tokens_.at(index);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size()) {
      Fail(context() + ": expected a number for " + std::string(what) + ", found '" +
           std::string(token) + "'");
    }
    if (!std::isfinite(value)) {
      Fail(context() + ": " + std::string(what) + " is '" + std::string(token) +
           "'; expected a finite number");
    }
    return value;
  }
  std::int64_t Id(std::size_t index, std::string_view what, std::int64_t max_id) const {
    const std::string_view token = tokens_.at(index);
    std::int64_t value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size() || value < 0 || value > max_id) {
      Fail(context() + ": expected a non-negative integer id for " + std::string(what) +
           " (at most " + std::to_string(max_id) + "), found '" + std::string(token) + "'");
    }
    return value;
  }

 private:
  const std::string& file_;
  int number_;
  std::vector<std::string_view> tokens_;
  std::string_view context_;
};

// Builds one line of space-separated fields: doubles in the shortest form
// that reads back to the same value, ids, information upper triangles and
// poses in g2o's order (x y theta; x y z qx qy qz qw).
class LineWriter {
 public:
  LineWriter() = default;
  explicit LineWriter(std::string_view tag) : text_(tag) {}
  LineWriter& operator<<(double value) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
    if (!text_.empty()) text_ += ' ';
    text_.append(buffer, result.ptr);
    return *this;
  }
  LineWriter& operator<<(std::int64_t id) {
    if (!text_.empty()) text_ += ' ';
    text_ += std::to_string(id);
    return *this;
  }
  template <typename Tag>
  LineWriter& operator<<(StrongId<Tag> id) { return *this << id.value(); }
  template <int N>
  LineWriter& operator<<(const Eigen::Matrix<double, N, N>& information) {
    for (int r = 0; r < N; ++r) {
      for (int c = r; c < N; ++c) *this << information(r, c);
    }
    return *this;
  }
  LineWriter& operator<<(const Pose2& pose) { return *this << pose.x() << pose.y() << pose.theta(); }
  LineWriter& operator<<(const Pose3& pose) {
    const auto& t = pose.translation();
    const auto& q = pose.rotation();
    return *this << t.x() << t.y() << t.z() << q.x() << q.y() << q.z() << q.w();
  }
  const std::string& str() const { return text_; }

 private:
  std::string text_;
};

// Reads the next line into `text` (without its newline); false at the end of
// the stream. A line longer than `max_bytes` is a FileError at line
// `number + 1`, read by characters so that a hostile line cannot grow without
// bound; `expected` says what a line should hold.
inline bool ReadBoundedLine(std::istream& in, std::string& text, std::size_t max_bytes,
                            const std::string& name, int number, std::string_view expected) {
  text.clear();
  char c;
  bool any = false;
  while (in.get(c)) {
    any = true;
    if (c == '\n') break;
    if (text.size() >= max_bytes) {
      throw FileError(name, number + 1,
                      "line longer than " + std::to_string(max_bytes) + " bytes; expected " +
                          std::string(expected));
    }
    text.push_back(c);
  }
  return any;
}

// Opens `path` for reading or throws a FileError saying why; `expected` names
// what the file should be ("a pose-graph file").
inline std::ifstream OpenForReading(const std::filesystem::path& path, std::string_view expected) {
  const std::string name = path.string();
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status)) {
    throw FileError(name, 0, "is a directory; expected " + std::string(expected));
  }
  // Opening a FIFO would wait for a writer forever; a device never ends.
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
    throw FileError(name, 0, "is not a regular file (a FIFO, device or socket); expected " + std::string(expected));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw FileError(name, 0,
                    std::filesystem::exists(path, ec)
                        ? "cannot open the file for reading (permission denied?)"
                        : "no such file; expected " + std::string(expected));
  }
  return in;
}

// The whole content of `path`, refused when larger than `max_bytes` (hostile
// input), with OpenForReading's errors; `expected` names what it should be.
inline std::string ReadWholeFile(const std::filesystem::path& path, std::uintmax_t max_bytes,
                                 std::string_view expected) {
  std::ifstream in = OpenForReading(path, expected);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > max_bytes) {
    throw FileError(path.string(), 0,
                    "is " + std::to_string(size) + " bytes; expected at most " +
                        std::to_string(max_bytes) + " for " + std::string(expected));
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The 1-based line of byte `offset` (0-based) in `text`.
inline int LineOfOffset(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n'));
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_INTERNAL_TEXT_LINE_H_
