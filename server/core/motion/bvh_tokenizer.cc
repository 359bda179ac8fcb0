// Splits BVH text into lines and tokens and matches the MOTION headers (see bvh_tokenizer.h).
#include "server/core/motion/bvh_tokenizer.h"

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"

namespace modskill::bvh_internal {
namespace {

// Keeps messages readable when a token is a megabyte of garbage.
constexpr size_t kMaxQuotedTokenChars = 40;

}  // namespace

std::string Quoted(absl::string_view token) {
  if (token.size() <= kMaxQuotedTokenChars) return absl::StrCat("'", token, "'");
  return absl::StrCat("'", token.substr(0, kMaxQuotedTokenChars), "...'");
}

bool IsBlank(absl::string_view line) { return absl::StripAsciiWhitespace(line).empty(); }

void SplitTokens(absl::string_view line, std::vector<absl::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && absl::ascii_isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !absl::ascii_isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

bool MatchHeader(absl::string_view line, std::initializer_list<absl::string_view> words,
                 absl::string_view* value) {
  absl::string_view rest = absl::StripAsciiWhitespace(line);
  for (absl::string_view word : words) {
    if (!absl::StartsWithIgnoreCase(rest, word)) return false;
    rest = absl::StripLeadingAsciiWhitespace(rest.substr(word.size()));
  }
  if (!absl::ConsumePrefix(&rest, ":")) return false;
  *value = absl::StripAsciiWhitespace(rest);
  return true;
}

bool TokenReader::Peek(Token* token) {
  while (index_ >= tokens_.size()) {
    absl::string_view line;
    if (!lines_->Next(&line)) return false;
    SplitTokens(line, &tokens_);
    index_ = 0;
  }
  *token = Token{tokens_[index_], lines_->line_number()};
  return true;
}

bool TokenReader::Next(Token* token) {
  if (!Peek(token)) return false;
  ++index_;
  return true;
}

std::vector<Token> TokenReader::RestOfLine() {
  std::vector<Token> rest;
  for (; index_ < tokens_.size(); ++index_) {
    rest.push_back(Token{tokens_[index_], lines_->line_number()});
  }
  return rest;
}

}  // namespace modskill::bvh_internal
