// Every parser fed mutated input (haptel bench fuzz's targets, a short run):
// the suite's guard that none crashes, hangs or lets through something it
// should refuse; `haptel bench fuzz` runs 10^6 inputs per target.
#include <catch2/catch.hpp>

#include "fuzz_bench.hpp"

using namespace haptel;

TEST_CASE("fuzz: every parser survives mutated input and still takes its valid seeds") {
  for (const std::string& target : bench::FuzzTargets()) {
    // The file targets write and parse a file per input, the console answers
    // each over a socket (500 a second; 20000 took 40 s of the suite's wall
    // time alone): fewer of them.
    const bool slow = target == "config" || target == "scene" || target == "console";
    const uint64_t inputs = slow ? 1500 : 20000;
    const bench::FuzzResult r = bench::Fuzz(target, inputs, 7);
    INFO(target);
    CHECK(r.inputs == inputs);
    CHECK(r.accepted + r.rejected == inputs);
    // One input in 64 is an unmutated seed, which must parse; most mutants must not.
    CHECK(r.accepted >= inputs / 64);
    CHECK(r.rejected > inputs / 4);
  }
  CHECK_THROWS_AS(bench::Fuzz("nothing", 1, 1), std::invalid_argument);
}
