// The command-line parser: numbers are whole words, options are known.
#include <catch2/catch.hpp>

#include "haptel/core/args.hpp"

using haptel::Args;
using haptel::UsageError;

namespace {

Args Parse(std::initializer_list<const char*> words) {
  std::vector<const char*> argv{"prog"};
  argv.insert(argv.end(), words.begin(), words.end());
  return Args(static_cast<int>(argv.size()), argv.data(), {"seconds", "count"}, {"json"});
}

}  // namespace

TEST_CASE("Args::Number takes a whole number in range and names the option otherwise") {
  CHECK(*Parse({"--seconds", "2.5"}).Number("seconds", 0.5, 10) == 2.5);
  CHECK(*Parse({"--seconds=1e0"}).Number("seconds", 0.5, 10) == 1.0);
  CHECK_FALSE(Parse({"--json"}).Number("seconds", 0.5, 10).has_value());
  CHECK_THROWS_AS(Parse({"--seconds", ""}), UsageError);  // an empty value is refused when parsed
  for (const char* bad : {"5x", "abc", "nan", "0.1", "11", " 5"}) {
    INFO(bad);
    CHECK_THROWS_WITH(
        Parse({"--seconds", bad}).Number("seconds", 0.5, 10),
        Catch::Contains("--seconds") && Catch::Contains("[0.5, 10]") && Catch::Contains(bad));
  }
}

TEST_CASE("Args::Int rejects trailing junk and out-of-range values") {
  CHECK(*Parse({"--count", "7"}).Int("count", 0, 10) == 7);
  CHECK_THROWS_AS(Parse({"--count", "7x"}).Int("count", 0, 10), UsageError);
  CHECK_THROWS_AS(Parse({"--count", "11"}).Int("count", 0, 10), UsageError);
}

TEST_CASE("Args: unknown options and missing values are usage errors") {
  CHECK_THROWS_AS(Parse({"--nope"}), UsageError);
  CHECK_THROWS_AS(Parse({"--seconds"}), UsageError);
  CHECK(Parse({"run", "--json"}).positional() == std::vector<std::string>{"run"});
}
