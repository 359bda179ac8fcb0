// Reading a viewer page back as its script does, for the tests that check what a page holds.
#ifndef MODSKILL_TESTS_VIEWER_PAGE_READING_H_
#define MODSKILL_TESTS_VIEWER_PAGE_READING_H_

#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "absl/strings/escaping.h"

namespace modskill {

// base64 of little-endian float32 (how the page stores poses) -> floats.
inline std::vector<float> DecodeFloats(const std::string& b64) {
  std::string bytes;
  EXPECT_TRUE(absl::Base64Unescape(b64, &bytes));
  std::vector<float> values(bytes.size() / 4);
  std::memcpy(values.data(), bytes.data(), values.size() * 4);  // little-endian, as the page reads it
  return values;
}

// The scene JSON exactly as the page's script reads it.
inline nlohmann::json PageScene(const std::string& html) {
  const std::string open = "<script id=\"modskill-scene\" type=\"application/json\">";
  const size_t begin = html.find(open);
  EXPECT_NE(begin, std::string::npos);
  const size_t end = html.find("</script>", begin);
  return nlohmann::json::parse(html.substr(begin + open.size(), end - begin - open.size()));
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_VIEWER_PAGE_READING_H_
