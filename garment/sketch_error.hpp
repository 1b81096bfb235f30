#pragma once
// The one error type for a sketch file a designer got wrong: it names the file, the JSON path of
// the offending value ("/panels/2/boundary/3") and says what is wrong in a plain sentence.

#include <stdexcept>
#include <string>

namespace sd::garment {

class SketchError : public std::invalid_argument {
 public:
  // `json_path` may be empty (a syntax error has a line and column instead, put in the sentence).
  SketchError(std::string file, std::string json_path, std::string sentence)
      : std::invalid_argument(compose(file, json_path, sentence)),
        file_(std::move(file)),
        json_path_(std::move(json_path)),
        sentence_(std::move(sentence)) {}

  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }
  const std::string& sentence() const { return sentence_; }

 private:
  static std::string compose(const std::string& file, const std::string& path,
                             const std::string& sentence) {
    std::string text = file + ": ";
    if (!path.empty()) text += path + ": ";
    return text + sentence;
  }

  std::string file_;
  std::string json_path_;
  std::string sentence_;
};

}  // namespace sd::garment
