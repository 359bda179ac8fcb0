// The BVH text as lines and whitespace-separated tokens, with line numbers for error messages.
// Private to the BVH parser (bvh_parser.cc); not part of the motion library's interface.
#ifndef MODSKILL_SERVER_CORE_MOTION_BVH_TOKENIZER_H_
#define MODSKILL_SERVER_CORE_MOTION_BVH_TOKENIZER_H_

#include <cstddef>
#include <initializer_list>
#include <string>
#include <vector>

#include "absl/strings/string_view.h"

namespace modskill::bvh_internal {

// `token` in single quotes, cut short so a megabyte of garbage keeps a message readable.
std::string Quoted(absl::string_view token);

bool IsBlank(absl::string_view line);

// Splits on ASCII whitespace (spaces, tabs, stray carriage returns), reusing `tokens`.
void SplitTokens(absl::string_view line, std::vector<absl::string_view>* tokens);

// Matches "<words...> : <value>" with free whitespace, e.g. "Frame Time:\t.0083"; sets the
// stripped value text.
bool MatchHeader(absl::string_view line, std::initializer_list<absl::string_view> words,
                 absl::string_view* value);

// Physical lines of the text; "\n", "\r\n" and a lone "\r" all end a line.
class LineReader {
 public:
  explicit LineReader(absl::string_view text) : text_(text) {}

  bool Next(absl::string_view* line) {
    if (position_ >= text_.size()) return false;
    const size_t end = text_.find_first_of("\r\n", position_);
    if (end == absl::string_view::npos) {
      *line = text_.substr(position_);
      position_ = text_.size();
    } else {
      *line = text_.substr(position_, end - position_);
      position_ = end + 1;
      if (text_[end] == '\r' && position_ < text_.size() && text_[position_] == '\n') ++position_;
    }
    ++line_number_;
    return true;
  }

  bool NextNonBlank(absl::string_view* line) {
    while (Next(line)) {
      if (!IsBlank(*line)) return true;
    }
    return false;
  }

  // 1-based number of the line last returned; 0 before the first.
  int line_number() const { return line_number_; }

 private:
  absl::string_view text_;
  size_t position_ = 0;
  int line_number_ = 0;
};

struct Token {
  absl::string_view text;
  int line = 0;
};

// Whitespace-separated tokens for the HIERARCHY part. Reads lines lazily so that, once MOTION
// is consumed, the LineReader sits on the line after it for the line-based MOTION part.
class TokenReader {
 public:
  explicit TokenReader(LineReader* lines) : lines_(lines) {}

  bool Peek(Token* token);
  bool Next(Token* token);
  // The tokens left on the line of the token last returned by Next, consumed.
  std::vector<Token> RestOfLine();

  int line_number() const { return lines_->line_number(); }

 private:
  LineReader* lines_;
  std::vector<absl::string_view> tokens_;
  size_t index_ = 0;
};

}  // namespace modskill::bvh_internal

#endif  // MODSKILL_SERVER_CORE_MOTION_BVH_TOKENIZER_H_
