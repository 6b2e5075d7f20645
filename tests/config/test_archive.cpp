// The archives over a config struct's Serialize (haptel/config/archive.hpp):
// one field list read strictly, checked and written back, on a struct of the
// test's own.
#include <yaml-cpp/yaml.h>

#include <array>
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"
#include "haptel/config/archives.hpp"
#include "haptel/config/error.hpp"
#include "test_env.hpp"

namespace haptel {
namespace {

using Catch::Contains;

enum class Mode { kSlow, kFast };

struct Inner {
  double gain = 0.5;
  std::array<double, 3> offset{0.0, 0.0, 0.0};

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(gain), config::Range{0.0, 1.0}, config::Comment{"per metre"});
    a->Visit(HAPTEL_NVP(offset), config::Range{-1.0, 1.0});
  }
  void ValidateOrThrow() const { config_detail::CheckFields(*this); }
};

struct Outer {
  std::filesystem::path file;
  std::string name;
  int count = 3;
  bool on = false;
  Mode mode = Mode::kSlow;
  std::filesystem::path log;
  std::array<double, 2> scales{1.0, 1.0};
  Inner inner;
  Inner left_hand;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(name), config::Required{}, config::NonEmpty{});
    a->Visit(HAPTEL_NVP(count), config::Range{1, 10});
    a->Visit(HAPTEL_NVP(on));
    a->Visit(HAPTEL_NVP(mode),
             config::Choice<Mode>{{{Mode::kSlow, "slow"}, {Mode::kFast, "fast"}}});
    a->Visit(HAPTEL_NVP(log), config::RelativeToFile{});
    a->Visit(HAPTEL_NVP(scales), config::Required{}, config::NonZero{}, config::EachElement{},
             config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(inner));
    a->Group("hands", [this](auto* hands) {
      hands->Visit(config::MakeNameValue("left", &left_hand),
                   config::Required{"the left hand (a mapping)"});
    });
  }
  void ValidateOrThrow() const { config_detail::CheckFields(*this); }
};

std::filesystem::path Write(const std::string& name, const std::string& text) {
  return test::WriteFile(test::ScratchDir("config-archive") / name, text);
}

constexpr const char* kGood = R"(name: probe
count: 4
on: true
mode: fast
log: logs
scales: [2.0, -0.5]
inner: {gain: 0.25, offset: [0.1, 0.2, 0.3]}
hands:
  left: {gain: 0.75}
)";

}  // namespace

TEST_CASE("A struct's Serialize is read strictly from a file, each field named once") {
  const auto file = Write("good.yaml", kGood);
  const Outer o = config_detail::LoadFile<Outer>(file);
  CHECK(o.file == file);
  CHECK(o.name == "probe");
  CHECK(o.count == 4);
  CHECK(o.on);
  CHECK(o.mode == Mode::kFast);
  CHECK(o.log == file.parent_path() / "logs");
  CHECK(o.scales == std::array<double, 2>{2.0, -0.5});
  CHECK(o.inner.gain == 0.25);
  CHECK(o.inner.offset == std::array<double, 3>{0.1, 0.2, 0.3});
  CHECK(o.left_hand.gain == 0.75);
  CHECK(o.left_hand.offset == std::array<double, 3>{0.0, 0.0, 0.0});  // default

  const auto error = [](const std::string& name, const std::string& text) {
    return test::WhatOf<ConfigError>([&] { config_detail::LoadFile<Outer>(Write(name, text)); });
  };
  // Unknown keys, at any depth, with the keys the struct has.
  CHECK_THAT(error("unknown.yaml", std::string(kGood) + "  lefty: 1\n"),
             Contains("key 'hands.lefty': unknown key (expected one of: left)"));
  CHECK_THAT(error("unknown-inner.yaml", "name: a\nscales: [1, 1]\ninner: {gian: 1}\n"),
             Contains(":3:9: key 'inner.gian': unknown key (expected one of: gain, offset)"));
  // Types, as read; ranges, once read, at the value's line.
  CHECK_THAT(error("type.yaml", "name: a\ncount: many\nscales: [1, 1]\n"),
             Contains(":2:8: key 'count': expected a whole number, got 'many'"));
  CHECK_THAT(error("choice.yaml", "name: a\nmode: medium\nscales: [1, 1]\n"),
             Contains("key 'mode': expected one of: slow, fast, got 'medium'"));
  CHECK_THAT(error("range.yaml", "name: a\nscales: [1, 1]\nhands: {left: {}}\ninner:\n  gain: 2\n"),
             Contains(":5:9: key 'inner.gain': expected a number in [0, 1], got '2'"));
  CHECK_THAT(error("element.yaml", "name: a\nscales: [1, 0]\nhands: {left: {}}\n"),
             Contains("key 'scales[1]': expected a non-zero number in [-5, 5]"));
  // Required keys, in the struct's words when it has some.
  CHECK_THAT(error("required.yaml", "scales: [1, 1]\n"),
             Contains("key 'name': expected a non-empty string, but it is missing"));
  CHECK_THAT(error("required-list.yaml", "name: a\n"),
             Contains("key 'scales': expected a list of 2 non-zero numbers, but it is missing"));
  CHECK_THAT(error("required-section.yaml", "name: a\nscales: [1, 1]\nhands: {}\n"),
             Contains("key 'hands.left': expected the left hand (a mapping), but it is missing"));
  // Duplicate keys: YamlMap::Load, before any field is read.
  CHECK_THAT(error("twice.yaml", "name: a\nname: b\n"), Contains("given twice"));
}

TEST_CASE("The field checker holds a struct built in code to the same rules") {
  Outer o;
  o.name = "code";
  o.left_hand.gain = 0.5;
  REQUIRE_NOTHROW(o.ValidateOrThrow());
  const auto key_of = [](const Outer& c) {
    try {
      c.ValidateOrThrow();
    } catch (const ConfigFieldError& e) {
      return e.key + ": " + e.expected;
    }
    return std::string("(valid)");
  };
  Outer bad = o;
  bad.left_hand.offset[2] = 3.0;
  CHECK(key_of(bad) == "hands.left.offset: a list of 3 numbers in [-1, 1]");
  bad = o;
  bad.count = 0;
  CHECK(key_of(bad) == "count: a whole number in [1, 10]");
  bad = o;
  bad.name.clear();
  CHECK(key_of(bad) == "name: a non-empty string");
  bad = o;
  bad.mode = static_cast<Mode>(7);
  CHECK(key_of(bad) == "mode: one of: slow, fast");
  bad = o;
  bad.scales[0] = 0.0;
  CHECK(key_of(bad) == "scales[0]: a non-zero number in [-5, 5]");
}

TEST_CASE("A struct written by its Serialize reads back equal, with its comments") {
  const auto file = Write("source.yaml", kGood);
  const Outer o = config_detail::LoadFile<Outer>(file);
  YAML::Emitter out;
  out << YAML::BeginMap;
  config_detail::YamlWriteArchive archive(out);
  const_cast<Outer&>(o).Serialize(&archive);
  out << YAML::EndMap;
  REQUIRE(out.good());
  CHECK_THAT(std::string(out.c_str()), Contains("gain: 0.25  # per metre"));
  // The log path is written as it is held (absolute here): it reads back the same.
  const Outer back = config_detail::LoadFile<Outer>(Write("written.yaml", out.c_str()));
  CHECK(back.name == o.name);
  CHECK(back.count == o.count);
  CHECK(back.on == o.on);
  CHECK(back.mode == o.mode);
  CHECK(back.scales == o.scales);
  CHECK(back.inner.gain == o.inner.gain);
  CHECK(back.inner.offset == o.inner.offset);
  CHECK(back.left_hand.gain == o.left_hand.gain);
}

}  // namespace haptel
