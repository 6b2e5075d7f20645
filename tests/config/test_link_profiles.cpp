// The link profiles in config/links/: every shipped one loads into a fault
// with a rate; --link-profile with --link-fault over it; an unknown name, a
// bad value or an unknown key in a profile file is one line naming what was
// expected.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/link.hpp"
#include "haptel/core/args.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;
using namespace haptel;

TEST_CASE("link profiles: the shipped ones all load, each with a rate, delay, jitter and loss") {
  const std::vector<std::string> names = LinkProfileNames();
  CHECK(names == std::vector<std::string>{"lan", "lte-uplink", "satellite", "wifi-busy"});
  for (const std::string& name : names) {
    INFO(name);
    const LinkFault fault = LoadLinkProfile(name);
    CHECK(fault.enabled);
    CHECK(fault.rate_bps > 0.0);
    CHECK(fault.delay_s > 0.0);
    CHECK(fault.jitter_s > 0.0);
    CHECK_NOTHROW(fault.ValidateOrThrow());
  }
  const LinkFault lte = LoadLinkProfile("lte-uplink");
  CHECK(lte.rate_bps == Approx(2e6));
  CHECK(lte.delay_s == Approx(0.03));
  CHECK(lte.loss == Approx(0.001));
  CHECK(LoadLinkProfile("satellite").queue_s == Approx(0.25));
}

TEST_CASE("link profiles: --link-fault's keys override the profile's, the rest stay") {
  LinkFault from_file;
  from_file.delay_s = 0.5;
  const LinkFault lte =
      LinkFaultFromOptions(std::string("lte-uplink"), std::string("loss=5%,rate=1Mbit"), from_file);
  CHECK(lte.rate_bps == Approx(1e6));
  CHECK(lte.loss == Approx(0.05));
  CHECK(lte.delay_s == Approx(0.03));  // the profile's, not the file's
  CHECK(LinkFaultFromOptions(std::nullopt, std::nullopt, from_file).delay_s == Approx(0.5));
  CHECK(LinkFaultFromOptions(std::nullopt, std::string("loss=1%"), from_file).delay_s ==
        0.0);  // as before profiles
  CHECK(LinkFaultFromOptions(std::string("lan"), std::nullopt, from_file).rate_bps ==
        Approx(100e6));
}

TEST_CASE("link profiles: an unknown name names the known ones; a bad file names its key") {
  try {
    LinkFaultFromOptions(std::string("dialup"), std::nullopt, {});
    FAIL("accepted");
  } catch (const UsageError& e) {
    CHECK_THAT(
        e.what(),
        Contains("option --link-profile: unknown link profile 'dialup': expected one of lan, "
                 "lte-uplink, satellite, wifi-busy"));
  }
  const auto dir = test::ScratchDir("link-profiles");
  const auto bad_rate = test::WriteFile(dir / "slow.yaml", "rate: 0\ndelay: 10ms\n");
  try {
    LoadLinkProfile(bad_rate.string());
    FAIL("accepted");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Contains("slow.yaml") && Contains("rate") &&
                             Contains("a rate from 1kbit to 10Gbit"));
  }
  const auto unknown_key = test::WriteFile(dir / "typo.yaml", "rate: 1Mbit\nlatency: 10ms\n");
  CHECK_THROWS_WITH(LoadLinkProfile(unknown_key.string()),
                    Contains("typo.yaml") && Contains("latency"));
  const LinkFault own =
      LoadLinkProfile(test::WriteFile(dir / "mine.yaml", "rate: 300kbit\nqueue: 1s\n").string());
  CHECK(own.rate_bps == Approx(3e5));
  CHECK(own.queue_s == Approx(1.0));
  CHECK(own.delay_s == 0.0);
}

TEST_CASE(
    "link faults: a key given twice and a number that is not plain decimal are refused (issue "
    "41)") {
  // Both were taken silently: the last rate won, and strtod read 0x10 as 16.
  CHECK_THROWS_WITH(ParseLinkFaultOption("rate=1Mbit,rate=2Mbit"),
                    Contains("option --link-fault: expected") && Contains("'rate' given twice"));
  CHECK_THROWS_WITH(ParseLinkFaultOption("delay=10ms,loss=1%,delay=20ms"),
                    Contains("'delay' given twice"));
  for (const char* text : {"delay=0x10ms", "rate=0x1p4Mbit", "loss=infinity%", "jitter=nanms",
                           "delay= 10ms", "loss=0x5%", "queue=0x10ms"}) {
    INFO(text);
    CHECK_THROWS_AS(ParseLinkFaultOption(std::string("rate=1Mbit,") + text), UsageError);
  }
  // Plain decimals, with an exponent, still read.
  CHECK(ParseLinkFault("delay=1e2ms,rate=.5Mbit,loss=5%").delay_s == Approx(0.1));
  CHECK(ParseLinkFault("delay=1e2ms,rate=.5Mbit,loss=5%").rate_bps == Approx(5e5));
}

TEST_CASE(
    "link profiles: a duplicate key is refused, and an unknown key lists the allowed ones (issue "
    "41)") {
  const auto dir = test::ScratchDir("link-profiles-strict");
  const auto twice = test::WriteFile(dir / "twice.yaml", "rate: 1Mbit\ndelay: 10ms\nrate: 2Mbit\n");
  CHECK_THROWS_WITH(LoadLinkProfile(twice.string()),
                    Contains("twice.yaml:3:1") && Contains("'rate'") && Contains("given twice") &&
                        Contains("line 1"));
  // Not the keys already read ("rate"): every key a profile may hold.
  const auto unknown_key = test::WriteFile(dir / "typo.yaml", "rate: 1Mbit\nlatency: 10ms\n");
  CHECK_THROWS_WITH(LoadLinkProfile(unknown_key.string()),
                    Contains("typo.yaml:2:1") && Contains("'latency': unknown key") &&
                        Contains("expected one of: delay, jitter, loss, queue, rate"));
  const auto hex = test::WriteFile(dir / "hex.yaml", "delay: 0x10ms\n");
  CHECK_THROWS_WITH(LoadLinkProfile(hex.string()), Contains("hex.yaml") && Contains("delay"));
}
