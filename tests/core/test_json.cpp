// JSON text as the programs write it: strings escaped, and never anything
// that is not UTF-8 (a scene's name with a stray byte made `haptel scene
// --json` print a line no JSON parser takes).
#include <catch2/catch.hpp>
#include <string>

#include "haptel/core/json.hpp"

using haptel::JsonString;

TEST_CASE("JsonString escapes quotes, backslashes and control characters") {
  CHECK(JsonString("a\"b\\c") == "\"a\\\"b\\\\c\"");
  CHECK(JsonString(std::string("tab\there\nend")) == "\"tab\\u0009here\\u000aend\"");
}

TEST_CASE("JsonString keeps well-formed UTF-8 and writes every other byte as U+FFFD") {
  // Two-, three- and four-byte sequences pass as they are.
  CHECK(JsonString("caf\xC3\xA9") == "\"caf\xC3\xA9\"");
  CHECK(JsonString("\xE6\x97\xA5\xE6\x9C\xAC") == "\"\xE6\x97\xA5\xE6\x9C\xAC\"");
  CHECK(JsonString("\xF0\x9F\x9A\x80") == "\"\xF0\x9F\x9A\x80\"");
  // A stray byte, a sequence cut short, an overlong form, a surrogate, past U+10FFFF.
  CHECK(JsonString("a\xFF"
                   "b") == "\"a\\ufffdb\"");
  CHECK(JsonString("cut \xE6\x97") == "\"cut \\ufffd\\ufffd\"");
  CHECK(JsonString("\xC0\xAF") == "\"\\ufffd\\ufffd\"");
  CHECK(JsonString("\xED\xA0\x80") == "\"\\ufffd\\ufffd\\ufffd\"");
  CHECK(JsonString("\xF4\x90\x80\x80") == "\"\\ufffd\\ufffd\\ufffd\\ufffd\"");
}
