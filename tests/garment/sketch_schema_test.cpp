// Every example sketch file validates against data/schema/sketchdrape-1.schema.json with the
// Python jsonschema package (Debian: python3-jsonschema), and files the parser rejects for
// shape reasons are rejected by the schema too. The examples have // comments: they are
// stripped by parsing with nlohmann::json first.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tests/garment/bad_cases.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::test {
namespace {

const std::filesystem::path kSchema =
    std::filesystem::path(SD_SOURCE_DIR) / "data/schema/sketchdrape-1.schema.json";

// A Python with jsonschema: Debian's first (scripts/setup.sh installs python3-jsonschema).
std::string python_with_jsonschema() {
  for (const char* candidate : {"/usr/bin/python3", "python3"}) {
    const std::string probe = std::string(candidate) + " -c 'import jsonschema' 2>/dev/null";
    if (std::system(probe.c_str()) == 0) return candidate;
  }
  return "";
}

// Exit code of validating `file` (a sketch, comments allowed) against the schema.
int validate_against_schema(const std::filesystem::path& file, const std::string& python) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, true, true);
  const std::filesystem::path plain =
      std::filesystem::temp_directory_path() / ("sd-schema-" + file.filename().string());
  std::ofstream(plain) << doc.dump(1);
  const std::string command =
      python +
      " -c 'import json, sys, jsonschema; "
      "jsonschema.validate(json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), "
      "cls=jsonschema.Draft202012Validator)' " +
      plain.string() + " " + kSchema.string() + " > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  std::filesystem::remove(plain);
  return status;
}

TEST(SketchSchema, SchemaIsAValidDraft202012Schema) {
  const std::string python = python_with_jsonschema();
  ASSERT_FALSE(python.empty()) << "python3-jsonschema is missing: run scripts/setup.sh";
  const std::string command =
      python +
      " -c 'import json, sys, jsonschema; "
      "jsonschema.Draft202012Validator.check_schema(json.load(open(sys.argv[1])))' " +
      kSchema.string();
  EXPECT_EQ(std::system(command.c_str()), 0);
}

TEST(SketchSchema, EveryExampleValidates) {
  const std::string python = python_with_jsonschema();
  ASSERT_FALSE(python.empty()) << "python3-jsonschema is missing: run scripts/setup.sh";
  const auto files = example_files();
  ASSERT_GE(files.size(), 5u);
  for (const auto& file : files) EXPECT_EQ(validate_against_schema(file, python), 0) << file;
}

TEST(SketchSchema, ShapeErrorsAreRejected) {
  const std::string python = python_with_jsonschema();
  ASSERT_FALSE(python.empty()) << "python3-jsonschema is missing: run scripts/setup.sh";
  // Errors of shape (not of geometry) must be caught by the schema as well.
  for (const char* name : {"unknown-key.json", "nan-string.json", "unknown-view.json",
                           "empty-panels.json", "grain-unknown.json", "grain-turn.json"}) {
    const auto file = std::filesystem::path(SD_SOURCE_DIR) / "tests/garment/bad" / name;
    EXPECT_NE(validate_against_schema(file, python), 0) << name;
  }
}

}  // namespace
}  // namespace sd::test
