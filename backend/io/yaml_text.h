// Reading YAML from a stranger: aliases refused before they are expanded.
//
// An alias (*name) lets a few hundred bytes stand for billions of nodes (the
// "billion laughs"); catgraph's configurations, scenarios and vocabularies
// never need one, so any alias is an error naming its line. So is anything
// after the first document: each of these files is one document, and
// yaml-cpp's document loop does not advance past a stray token at document
// level (", 1" would loop for ever). Header-only: every target that reads
// YAML links yaml-cpp itself.
#ifndef CATGRAPH_BACKEND_IO_YAML_TEXT_H_
#define CATGRAPH_BACKEND_IO_YAML_TEXT_H_

#include <sstream>
#include <string>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "backend/io/file_error.h"

namespace catgraph {

// Parses `text` (from `source`, named in errors); throws FileError with the
// line for a syntax error or an alias.
inline YAML::Node LoadYamlWithoutAliases(const std::string& text, const std::string& source) {
  struct AliasRefuser : YAML::EventHandler {
    explicit AliasRefuser(const std::string& s) : source(s) {}
    void OnDocumentStart(const YAML::Mark&) override {}
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
    void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override {
      throw FileError(source, mark.line + 1, "a YAML alias (*name); expected plain values (aliases are refused)");
    }
    void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
    void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
    void OnMapEnd() override {}
    const std::string& source;
  };
  try {
    struct SecondDocumentRefuser : AliasRefuser {
      using AliasRefuser::AliasRefuser;
      void OnDocumentStart(const YAML::Mark& mark) override {
        throw FileError(source, mark.line + 1, "text after the first YAML document; expected one document");
      }
    };
    std::istringstream in(text);
    YAML::Parser parser(in);
    AliasRefuser refuser(source);
    parser.HandleNextDocument(refuser);
    SecondDocumentRefuser second(source);
    parser.HandleNextDocument(second);
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FileError(source, e.mark.is_null() ? 0 : e.mark.line + 1, "expected YAML: " + e.msg);
  }
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_YAML_TEXT_H_
