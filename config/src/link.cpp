#include "haptel/config/link.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/yaml_map.hpp"
#include "haptel/core/args.hpp"

namespace haptel {

namespace check = config_check;

namespace {
// A rate below 1 kbit/s passes one command a second at best: a typo, not a link.
constexpr double kMinRateBps = 1e3;
constexpr double kMaxRateBps = 10e9;
// A queue shorter than a millisecond holds no video frame at any rate here.
constexpr double kMinQueueS = 1e-3;
}  // namespace

namespace {
/// Every element of `addresses` (the list under `key`) is a dotted IPv4
/// address: DDS would otherwise drop a bad interface silently (nothing is
/// ever heard) or fail only once the vehicle is spawned.
void CheckIpv4List(const std::string& key, const std::vector<std::string>& addresses) {
  for (size_t i = 0; i < addresses.size(); ++i) {
    in_addr parsed{};
    if (inet_pton(AF_INET, addresses[i].c_str(), &parsed) != 1) {
      check::Fail(key + "[" + std::to_string(i) + "]", "an IPv4 address such as 127.0.0.1");
    }
  }
}
}  // namespace

void LinkConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  CheckIpv4List("interfaces", interfaces);
  CheckIpv4List("peers", peers);
  if (!discovery_server.empty()) {
    try {
      ParseServerAddress(discovery_server);
    } catch (const std::invalid_argument& e) {
      check::Fail("discovery_server", e.what());
    }
  }
}

std::pair<std::string, int> ParseServerAddress(const std::string& text) {
  const size_t colon = text.rfind(':');
  const std::string address = text.substr(0, colon);
  in_addr parsed{};
  int port = 0;
  if (colon != std::string::npos) {
    try {
      size_t used = 0;
      port = std::stoi(text.substr(colon + 1), &used);
      if (used != text.size() - colon - 1) port = 0;
    } catch (const std::exception&) {
      port = 0;
    }
  }
  if (colon == std::string::npos || inet_pton(AF_INET, address.c_str(), &parsed) != 1 || port < 1 ||
      port > 65535) {
    throw std::invalid_argument("an IPv4 address and a port, such as 192.168.1.10:11811 (not '" +
                                text + "')");
  }
  return {address, port};
}

void LinkFault::ValidateOrThrow() const {
  check::Number("delay_s", delay_s, 0.0, 10.0);
  check::Number("jitter_s", jitter_s, 0.0, 10.0);
  check::Number("loss", loss, 0.0, 0.99);
  if (rate_bps != 0.0) check::Number("rate_bps", rate_bps, kMinRateBps, kMaxRateBps);
  check::Number("queue_s", queue_s, kMinQueueS, 10.0);
}

namespace {

/// A number and the unit written right after it ("100ms" -> 100, "ms").
/// `parsed` is false when `value` does not start with a number.
struct NumberWithUnit {
  double number = 0.0;
  std::string unit;
  bool parsed = false;
};
NumberWithUnit SplitNumber(const std::string& value) {
  NumberWithUnit out;
  // Plain decimals only: strtod would read "0x10ms" as 16 ms and "infms" as ever.
  size_t used = DecimalPrefix(value);
  try {
    if (used > 0) out.number = std::stod(value.substr(0, used));
  } catch (const std::exception&) {
    used = 0;  // out of a double's range
  }
  out.parsed = used > 0;
  out.unit = value.substr(used);
  return out;
}

/// "100ms", "0.1s", "250us" -> seconds; throws naming `part`.
double ParseDuration(const std::string& part, const std::string& value) {
  const NumberWithUnit v = SplitNumber(value);
  double scale = 0.0;
  if (v.unit == "s") scale = 1.0;
  if (v.unit == "ms") scale = 1e-3;
  if (v.unit == "us") scale = 1e-6;
  if (!v.parsed || scale == 0.0 || !std::isfinite(v.number) || v.number < 0.0) {
    throw std::invalid_argument("a time >= 0 with its unit, such as 100ms, 0.1s or 250us (not '" +
                                part + "')");
  }
  return v.number * scale;
}

/// "5%" or "0.05" -> fraction; throws naming `part`.
double ParseFraction(const std::string& part, const std::string& value) {
  const NumberWithUnit v = SplitNumber(value);
  const double number = v.unit == "%" ? v.number / 100.0 : v.number;
  if (!v.parsed || (!v.unit.empty() && v.unit != "%") || !(number >= 0.0 && number <= 0.99)) {
    throw std::invalid_argument("a loss from 0 to 99%, such as 5% or 0.05 (not '" + part + "')");
  }
  return number;
}

/// "1Mbit", "500kbit", "0.5Mbit" -> bit/s; throws naming `part`. tc's
/// lower-case "mbit" and "gbit" are taken too (nobody means millibits).
double ParseRate(const std::string& part, const std::string& value) {
  const NumberWithUnit v = SplitNumber(value);
  double scale = 0.0;
  if (v.unit == "kbit") scale = 1e3;
  if (v.unit == "Mbit" || v.unit == "mbit") scale = 1e6;
  if (v.unit == "Gbit" || v.unit == "gbit") scale = 1e9;
  const double rate = v.number * scale;
  if (!v.parsed || scale == 0.0 || !std::isfinite(v.number) ||
      !(rate >= kMinRateBps && rate <= kMaxRateBps)) {
    throw std::invalid_argument(
        "a rate from 1kbit to 10Gbit with its unit, such as 1Mbit or 500kbit (not '" + part + "')");
  }
  return rate;
}

}  // namespace

LinkFault ParseLinkFault(const std::string& text, const LinkFault& base) {
  LinkFault fault = base;
  fault.enabled = true;
  if (text == "on") return fault;
  bool queue_given = false;
  std::vector<std::string> seen;
  for (const std::string& part : SplitList(text)) {
    const size_t eq = part.find('=');
    const std::string key = part.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : part.substr(eq + 1);
    // Twice is a typo or a paste, never a wish for the last one.
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
      throw std::invalid_argument("each key once ('" + key + "' given twice in '" + text + "')");
    }
    seen.push_back(key);
    if (key == "delay" && eq != std::string::npos) {
      fault.delay_s = ParseDuration(part, value);
    } else if (key == "jitter" && eq != std::string::npos) {
      fault.jitter_s = ParseDuration(part, value);
    } else if (key == "loss" && eq != std::string::npos) {
      fault.loss = ParseFraction(part, value);
    } else if (key == "rate" && eq != std::string::npos) {
      fault.rate_bps = ParseRate(part, value);
    } else if (key == "queue" && eq != std::string::npos) {
      double queue_s = 0.0;
      try {
        queue_s = ParseDuration(part, value);
      } catch (const std::invalid_argument&) {
        queue_s = 0.0;
      }
      if (!(queue_s >= kMinQueueS && queue_s <= 10.0)) {
        throw std::invalid_argument(
            "a queue depth from 1ms to 10s with its unit, such as 100ms (not '" + part + "')");
      }
      fault.queue_s = queue_s;
      queue_given = true;
    } else {
      throw std::invalid_argument(
          "rate=RATE, queue=TIME, delay=TIME, jitter=TIME or loss=PERCENT, comma-separated "
          "(e.g. rate=1Mbit,delay=100ms,jitter=20ms,loss=5%), or 'on' (not '" +
          part + "')");
    }
  }
  if (queue_given && fault.rate_bps == 0.0) {
    throw std::invalid_argument("queue=TIME only with a rate=RATE it is the depth at (not '" +
                                text + "')");
  }
  if (fault.delay_s > 10.0 || fault.jitter_s > 10.0) {
    throw std::invalid_argument("a delay and jitter of at most 10 s (not '" + text + "')");
  }
  return fault;
}

LinkFault ParseLinkFaultOption(const std::string& text, const LinkFault& base) {
  try {
    return ParseLinkFault(text, base);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("option --link-fault: expected ") + e.what());
  }
}

std::vector<std::string> LinkProfileNames() {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry :
       std::filesystem::directory_iterator(ShippedFile("config/links"), error)) {
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

LinkFault LoadLinkProfile(const std::string& name_or_file) {
  const bool is_file = name_or_file.find('/') != std::string::npos ||
                       std::filesystem::path(name_or_file).extension() == ".yaml";
  const std::filesystem::path file = is_file
                                         ? std::filesystem::path(name_or_file)
                                         : ShippedFile("config/links/" + name_or_file + ".yaml");
  if (!is_file && !std::filesystem::exists(file)) {
    throw ConfigError("unknown link profile '" + name_or_file + "': expected one of " +
                      JoinList(LinkProfileNames(), ", ") +
                      " (config/links/), or a profile file's path");
  }
  config_detail::YamlMap root = config_detail::YamlMap::Load(file);
  // Each key through ParseLinkFault, so a file and --link-fault take the same words.
  LinkFault fault;
  fault.enabled = true;
  for (const char* key : {"rate", "queue", "delay", "jitter", "loss"}) {
    root.Allow(key);  // an unknown key's error lists them all
    if (!root.Has(key)) continue;
    const std::string value = root.RequireString(key);
    try {
      fault = ParseLinkFault(std::string(key) + "=" + value, fault);
    } catch (const std::invalid_argument& e) {
      root.Fail(key, e.what());
    }
  }
  root.Finish();
  return fault;
}

LinkFault LinkFaultFromOptions(const std::optional<std::string>& profile,
                               const std::optional<std::string>& fault,
                               const LinkFault& otherwise) {
  if (!profile && !fault) return otherwise;
  LinkFault base;
  if (profile) {
    try {
      base = LoadLinkProfile(*profile);
    } catch (const ConfigError& e) {
      throw UsageError(std::string("option --link-profile: ") + e.what());
    }
  }
  return fault ? ParseLinkFaultOption(*fault, base) : base;
}

std::string LinkFaultProblem(const LinkFault& fault, double state_rate_hz,
                             double vehicle_timeout_s) {
  if (!fault.enabled) return "";
  char text[400];
  // States in one time-out window, each dropped with probability `loss`: the
  // window passes empty with loss^n, and there are 60 / timeout a minute.
  const double per_window = std::max(1.0, std::floor(state_rate_hz * vehicle_timeout_s));
  const double empty_per_minute = std::pow(fault.loss, per_window) * 60.0 / vehicle_timeout_s;
  if (fault.loss > 0.0 && empty_per_minute >= 1.0) {
    const double max_loss = std::pow(vehicle_timeout_s / 60.0, 1.0 / per_window);
    std::snprintf(text, sizeof text,
                  "a loss of %.0f%% drops all %.0f states of a %.2f-s vehicle time-out (%.0f Hz) "
                  "about %.0f times a "
                  "minute: the vehicle would be declared lost though it runs; expected a loss "
                  "under %.0f%% (or a "
                  "longer --vehicle-timeout)",
                  fault.loss * 100.0, per_window, vehicle_timeout_s, state_rate_hz,
                  empty_per_minute, std::floor(max_loss * 100.0));
    return text;
  }
  if (fault.jitter_s >= vehicle_timeout_s) {
    std::snprintf(text, sizeof text,
                  "a jitter of %.3g s holds a state back as long as the %.2f-s vehicle time-out: "
                  "the vehicle would be "
                  "declared lost though it runs; expected a jitter under %.2f s (or a longer "
                  "--vehicle-timeout)",
                  fault.jitter_s, vehicle_timeout_s, vehicle_timeout_s);
    return text;
  }
  return "";
}

std::vector<std::string> ParseAddressOption(const std::string& option, const std::string& text) {
  const std::vector<std::string> out = SplitList(text);
  for (const std::string& address : out) {
    in_addr parsed{};
    if (inet_pton(AF_INET, address.c_str(), &parsed) != 1) {
      throw UsageError("option --" + option +
                       ": expected IPv4 addresses such as 192.168.1.20, comma-separated (not '" +
                       address + "')");
    }
  }
  return out;
}

std::string ServerOption(const std::string& text) {
  try {
    ParseServerAddress(text);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("option --discovery-server: expected ") + e.what());
  }
  return text;
}

std::string LinkFaultText(const LinkFault& fault) {
  char text[200];
  int used = std::snprintf(text, sizeof text, "delay=%.9gs,jitter=%.9gs,loss=%.9g", fault.delay_s,
                           fault.jitter_s, fault.loss);
  // Without a rate, the text is what it was before rates existed (recorded runs compare equal).
  if (fault.rate_bps > 0.0) {
    std::snprintf(text + used, sizeof text - static_cast<size_t>(used),
                  ",rate=%.9gkbit,queue=%.9gs", fault.rate_bps / 1e3, fault.queue_s);
  }
  return text;
}

}  // namespace haptel
