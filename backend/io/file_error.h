// The one error type of catgraph's file readers and writers.
//
// Its message always names the file and, where the problem is on a line, the
// 1-based line number, in the compiler style "path:line: what was expected",
// so that editors and terminals can jump to it.
#ifndef CATGRAPH_BACKEND_IO_FILE_ERROR_H_
#define CATGRAPH_BACKEND_IO_FILE_ERROR_H_

#include <stdexcept>
#include <string>

namespace catgraph {

// `text` with control bytes (ESC, BEL, a newline a file name or token may
// carry) written as \xNN, so that a message is one harmless line.
inline std::string PrintableText(const std::string& text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) {
      out += "\\x";
      out += kHex[byte >> 4];
      out += kHex[byte & 0xf];
    } else {
      out += c;
    }
  }
  return out;
}

class FileError : public std::runtime_error {
 public:
  // line == 0: the problem concerns the whole file (missing, unreadable,
  // empty of content).
  FileError(std::string file, int line, const std::string& message)
      : std::runtime_error(Format(file, line, message)),
        file_(std::move(file)),
        line_(line) {}

  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  static std::string Format(const std::string& file, int line, const std::string& message) {
    return PrintableText(line > 0 ? file + ":" + std::to_string(line) + ": " + message : file + ": " + message);
  }


  std::string file_;
  int line_ = 0;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_FILE_ERROR_H_
