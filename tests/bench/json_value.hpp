#pragma once
// A strict JSON reader (RFC 8259) for the benchmarks' one-line reports: they
// nest objects and lists, which core/json.hpp's JsonFieldOf (flat objects
// only) cannot read. Test code only; the product writes JSON and never
// needs to read more than JsonFieldOf does.
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace haptel::test {

class JsonValue {
 public:
  enum class Kind { kNull, kBool, kNumber, kString, kArray, kObject };

  /// The value `text` holds, all of it (trailing text, a missing comma or an
  /// unquoted key is an error). Throws std::runtime_error naming the offset.
  static JsonValue Parse(const std::string& text) {
    Reader r{text};
    r.Space();
    JsonValue v = r.Value(0);
    r.Space();
    if (r.at != text.size()) r.Fail("text after the value");
    return v;
  }

  Kind kind() const { return kind_; }
  bool is_number() const { return kind_ == Kind::kNumber; }
  bool is_string() const { return kind_ == Kind::kString; }
  bool is_array() const { return kind_ == Kind::kArray; }
  bool is_object() const { return kind_ == Kind::kObject; }

  /// The value as a type; throws std::runtime_error when it is another.
  bool boolean() const { return Want(Kind::kBool, "a boolean").bool_; }
  double number() const { return Want(Kind::kNumber, "a number").number_; }
  const std::string& string() const { return Want(Kind::kString, "a string").string_; }
  const std::vector<JsonValue>& array() const { return Want(Kind::kArray, "a list").array_; }
  /// An object's members, in the text's order.
  const std::vector<std::pair<std::string, JsonValue>>& object() const {
    return Want(Kind::kObject, "an object").object_;
  }

  /// The member `key` of an object, or null when it has none.
  const JsonValue* find(const std::string& key) const {
    for (const auto& [k, v] : object()) {
      if (k == key) return &v;
    }
    return nullptr;
  }
  bool has(const std::string& key) const { return is_object() && find(key) != nullptr; }
  /// The member `key` of an object; throws std::runtime_error naming the key when absent.
  const JsonValue& operator[](const std::string& key) const {
    const JsonValue* v = find(key);
    if (v == nullptr) throw std::runtime_error("JSON: no key \"" + key + "\"");
    return *v;
  }
  const JsonValue& operator[](size_t i) const { return array().at(i); }

 private:
  struct Reader {
    const std::string& text;
    size_t at = 0;

    [[noreturn]] void Fail(const std::string& what) const {
      throw std::runtime_error("JSON: " + what + " at offset " + std::to_string(at));
    }
    void Space() {
      while (at < text.size() &&
             (text[at] == ' ' || text[at] == '\t' || text[at] == '\n' || text[at] == '\r'))
        ++at;
    }
    bool Eat(char c) {
      if (at < text.size() && text[at] == c) {
        ++at;
        return true;
      }
      return false;
    }
    void Expect(char c) {
      if (!Eat(c)) Fail(std::string("expected '") + c + "'");
    }
    bool Word(const char* word) {
      const std::string w(word);
      if (text.compare(at, w.size(), w) != 0) return false;
      at += w.size();
      return true;
    }

    JsonValue Value(int depth) {
      if (depth > 64) Fail("nesting deeper than 64");
      if (at >= text.size()) Fail("a value expected, the text ended");
      JsonValue v;
      const char c = text[at];
      if (c == '{') {
        v.kind_ = Kind::kObject;
        ++at;
        Space();
        if (Eat('}')) return v;
        do {
          Space();
          if (at >= text.size() || text[at] != '"') Fail("a quoted key expected");
          std::string key = String();
          Space();
          Expect(':');
          Space();
          if (v.find(key) != nullptr) Fail("key \"" + key + "\" twice");
          JsonValue member = Value(depth + 1);
          v.object_.emplace_back(std::move(key), std::move(member));
          Space();
        } while (Eat(','));
        Expect('}');
      } else if (c == '[') {
        v.kind_ = Kind::kArray;
        ++at;
        Space();
        if (Eat(']')) return v;
        do {
          Space();
          v.array_.push_back(Value(depth + 1));
          Space();
        } while (Eat(','));
        Expect(']');
      } else if (c == '"') {
        v.kind_ = Kind::kString;
        v.string_ = String();
      } else if (Word("true")) {
        v.kind_ = Kind::kBool;
        v.bool_ = true;
      } else if (Word("false")) {
        v.kind_ = Kind::kBool;
      } else if (Word("null")) {
        v.kind_ = Kind::kNull;
      } else {
        v.kind_ = Kind::kNumber;
        v.number_ = Number();
      }
      return v;
    }

    std::string String() {
      Expect('"');
      std::string out;
      while (true) {
        if (at >= text.size()) Fail("unterminated string");
        const char c = text[at++];
        if (c == '"') return out;
        if (static_cast<unsigned char>(c) < 0x20) Fail("a control character in a string");
        if (c != '\\') {
          out += c;
          continue;
        }
        if (at >= text.size()) Fail("unterminated escape");
        const char e = text[at++];
        switch (e) {
          case '"':
          case '\\':
          case '/':
            out += e;
            break;
          case 'b':
            out += '\b';
            break;
          case 'f':
            out += '\f';
            break;
          case 'n':
            out += '\n';
            break;
          case 'r':
            out += '\r';
            break;
          case 't':
            out += '\t';
            break;
          case 'u': {
            if (at + 4 > text.size()) Fail("a short \\u escape");
            unsigned code = 0;
            for (int i = 0; i < 4; ++i) {
              const char h = text[at++];
              code <<= 4;
              if (h >= '0' && h <= '9')
                code |= static_cast<unsigned>(h - '0');
              else if (h >= 'a' && h <= 'f')
                code |= static_cast<unsigned>(h - 'a' + 10);
              else if (h >= 'A' && h <= 'F')
                code |= static_cast<unsigned>(h - 'A' + 10);
              else
                Fail("a bad \\u escape");
            }
            // The reports escape control characters only: keep the low byte.
            out += static_cast<char>(code & 0xff);
            break;
          }
          default:
            Fail("an unknown escape");
        }
      }
    }

    /// -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?
    double Number() {
      const size_t start = at;
      auto digits = [&] {
        const size_t from = at;
        while (at < text.size() && text[at] >= '0' && text[at] <= '9') ++at;
        return at - from;
      };
      Eat('-');
      if (Eat('0')) {
        if (at < text.size() && text[at] >= '0' && text[at] <= '9')
          Fail("a number with a leading zero");
      } else if (digits() == 0) {
        Fail("a value expected");
      }
      if (Eat('.') && digits() == 0) Fail("a number with no digits after '.'");
      if (at < text.size() && (text[at] == 'e' || text[at] == 'E')) {
        ++at;
        if (!Eat('+')) Eat('-');
        if (digits() == 0) Fail("a number with no exponent digits");
      }
      return std::strtod(text.substr(start, at - start).c_str(), nullptr);
    }
  };

  const JsonValue& Want(Kind kind, const char* what) const {
    if (kind_ != kind) throw std::runtime_error(std::string("JSON: expected ") + what);
    return *this;
  }

  Kind kind_ = Kind::kNull;
  bool bool_ = false;
  double number_ = 0.0;
  std::string string_;
  std::vector<JsonValue> array_;
  std::vector<std::pair<std::string, JsonValue>> object_;
};

}  // namespace haptel::test
