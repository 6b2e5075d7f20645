#include "servo_bench.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bare_loop.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/alloc_counter.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/udp/udp_device.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

using haptics::Side;

struct ModeResult {
  std::string name;
  std::string description;
  LoopStats stats;
  uint64_t allocations = 0;
  uint64_t udp_unanswered = 0;
  uint64_t udp_malformed = 0;
  bool memory_locked = false;
  std::vector<double> histogram;  ///< counts per 10 µs bin
};

ModeResult Measure(const std::string& name, const std::string& description, haptics::Device& device,
                   const DeviceConfig& config, double seconds) {
  const ServoLoopRun run = MeasureServoLoop(device, config, seconds);
  ModeResult r;
  r.name = name;
  r.description = description;
  r.stats = run.stats;
  r.allocations = run.allocations;
  r.memory_locked = run.memory_locked;
  r.histogram = run.histogram;
  return r;
}

std::string Json(const ModeResult& r, double bare_p99_us) {
  std::ostringstream o;
  o << "{\"rate_hz\":" << r.stats.rate_hz
    << ",\"p99_ratio_to_bare\":" << (bare_p99_us > 0 ? r.stats.period_p99_us / bare_p99_us : 0.0)
    << ",\"period_p50_us\":" << r.stats.period_p50_us
    << ",\"period_p99_us\":" << r.stats.period_p99_us
    << ",\"period_max_us\":" << r.stats.period_max_us << ",\"overruns\":" << r.stats.overruns
    << ",\"allocations_in_loop\":" << r.allocations
    << ",\"realtime\":" << (r.stats.realtime ? "true" : "false")
    << ",\"memory_locked\":" << (r.memory_locked ? "true" : "false")
    << ",\"udp_unanswered\":" << r.udp_unanswered << ",\"udp_malformed\":" << r.udp_malformed
    << "}";
  return o.str();
}

}  // namespace

ServoLoopRun MeasureServoLoop(haptics::Device& device, const DeviceConfig& config, double seconds) {
  ServoLoopRun r;
  haptics::Hal hal;
  haptics::ServoLoop loop(device, hal, config, DeviceCalibration{});
  haptics::ForceField field;
  field.enabled = true;
  field.stiffness = 40.0;
  field.damping = 2.0;
  loop.Start();
  // Let the threads start and warm their caches before counting allocations.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const uint64_t allocations_before = alloc::TotalAllocations();
  const int64_t end = MonotonicNs() + SToNs(seconds);
  while (MonotonicNs() < end) {
    for (int i = 0; i < haptics::kSides; ++i) {
      if (device.HasSide(static_cast<Side>(i))) hal.SetField(static_cast<Side>(i), field);
    }
    SleepUntilNs(MonotonicNs() + SToNs(0.01));
  }
  r.allocations = alloc::TotalAllocations() - allocations_before;
  r.memory_locked = loop.memory_locked();
  loop.Stop();
  r.stats = loop.Stats();
  const Histogram& h =
      loop.period_histogram(device.HasSide(Side::kLeft) ? Side::kLeft : Side::kRight);
  for (int i = 0; i <= h.bins(); ++i) r.histogram.push_back(static_cast<double>(h.BinCount(i)));
  return r;
}

int BenchServoMain(int argc, const char* const* argv) {
  double seconds = 3.0;
  bool json = false, smoke = false;
  DeviceConfig base;
  try {
    const Args args(argc, argv, {"seconds", "device"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke) seconds = 0.5;  // every mode still runs, each for the shortest --seconds allowed
    if (auto v = args.Number("seconds", 0.5, 600)) seconds = *v;
    base =
        LoadDevice(args.Value("device").value_or(ShippedFile("config/devices/sim.yaml").string()));
  } catch (const UsageError& e) {
    std::fprintf(stderr, "haptel bench servo: %s\n", e.what());
    return 2;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "haptel bench servo: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench servo: %s\n", e.what());
    return 2;
  }
  base.driver = "sim";
  PrintSmokeNote("servo", smoke, "every mode for %.1f s", seconds);
  std::vector<ModeResult> results;

  {  // The reference: an empty clock_nanosleep loop with the same rate and scheduling.
    const BareLoop bare =
        MeasureBareLoop(base.servo.rate_hz, base.servo.realtime_priority, seconds);
    ModeResult r;
    r.name = "bare_clock_nanosleep";
    r.description = "an empty loop: the machine's timing floor";
    r.stats = bare.stats;
    r.histogram = bare.histogram;
    results.push_back(r);
  }

  {  // (a) one local sim arm, its own thread
    DeviceConfig c = base;
    c.sides = {false, true};
    c.servo.two_sided = false;
    haptics::SimDevice dev(c, OperatorConfig{});
    results.push_back(Measure("local_one_arm", "one sim arm, one thread", dev, c, seconds));
  }
  {  // (b) two sim arms, two-sided
    DeviceConfig c = base;
    c.sides = {true, true};
    c.servo.two_sided = true;
    haptics::SimDevice dev(c, OperatorConfig{});
    results.push_back(Measure("local_two_arms", "two sim arms, two-sided", dev, c, seconds));
  }
  // (c) two arms behind two device servers on loopback, decimation on and off.
  const std::string server = (ProgramDirectory() / "haptel-device-server").string();
  const int port_base = 20000 + static_cast<int>(getpid() % 20000);
  for (const int divider : {base.servo.slow_channel_divider, 1}) {
    std::vector<std::unique_ptr<ChildProcess>> servers;
    const char* names[2] = {"left", "right"};
    for (int i = 0; i < 2; ++i) {
      servers.push_back(std::make_unique<ChildProcess>(
          server,
          std::vector<std::string>{"--side", names[i], "--port", std::to_string(port_base + i),
                                   "--device", base.file.string()}));
    }
    DeviceConfig c = base;
    c.driver = "udp";
    c.sides = {true, true};
    c.servo.two_sided = true;
    c.servo.slow_channel_divider = divider;
    c.udp.arms[0] = {"127.0.0.1", port_base};
    c.udp.arms[1] = {"127.0.0.1", port_base + 1};
    haptics::UdpDevice dev(c);
    // Wait for both servers to answer (they take a moment to start).
    const int64_t give_up = MonotonicNs() + SToNs(10.0);
    haptics::WristRaw raw;
    bool up = false;
    while (!up && MonotonicNs() < give_up) {
      up = dev.ReadWrist(Side::kLeft, MonotonicNs(), raw) == haptics::DeviceStatus::kOk &&
           dev.ReadWrist(Side::kRight, MonotonicNs(), raw) == haptics::DeviceStatus::kOk;
      if (!up) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!up) {
      std::fprintf(stderr,
                   "haptel bench servo: the device servers on ports %d and %d did not answer\n",
                   port_base, port_base + 1);
      return 1;
    }
    const auto before = dev.Counters();
    ModeResult r =
        Measure(divider == 1 ? "udp_two_arms_every_cycle" : "udp_two_arms_decimated",
                divider == 1 ? "two UDP arms, glove every cycle"
                             : "two UDP arms, glove every " + std::to_string(divider) + "th",
                dev, c, seconds);
    const auto after = dev.Counters();
    r.udp_unanswered = after.unanswered - before.unanswered;
    r.udp_malformed = after.malformed_total() - before.malformed_total();
    results.push_back(r);
  }

  // Table.
  std::printf("haptel bench servo: %.1f s per mode, target rate %.0f Hz\n\n", seconds,
              base.servo.rate_hz);
  const double bare_p99 = results[0].stats.period_p99_us;
  auto ratio = [&](const ModeResult& r) {
    return bare_p99 > 0 ? r.stats.period_p99_us / bare_p99 : 0.0;
  };
  std::printf("%-26s %9s %8s %8s %7s %9s %9s %7s %9s %-8s %s\n", "mode", "rate Hz", "p50 us",
              "p99 us", "x bare", "max us", "overruns", "allocs", "udp lost", "realtime", "mlock");
  for (const ModeResult& r : results) {
    std::printf("%-26s %9.1f %8.0f %8.0f %7.2f %9.0f %9llu %7llu %9llu %-8s %s\n", r.name.c_str(),
                r.stats.rate_hz, r.stats.period_p50_us, r.stats.period_p99_us, ratio(r),
                r.stats.period_max_us, static_cast<unsigned long long>(r.stats.overruns),
                static_cast<unsigned long long>(r.allocations),
                static_cast<unsigned long long>(r.udp_unanswered), r.stats.realtime ? "yes" : "no",
                r.memory_locked ? "yes" : "no");
  }
  std::printf(
      "\n  rate: cycles per second over the run; p50/p99/max: start-to-start period;\n"
      "  x bare: p99 over the empty loop's p99 in this run (the machine's floor);\n"
      "  overruns: cycles started over one period late (or skipped); allocs: heap\n"
      "  allocations anywhere in the process while the loop ran (must be 0);\n"
      "  udp lost: requests that got no valid reply after their retries.\n");

  // CSV and plot.
  const auto dir = OutputDir(smoke);
  {
    std::ofstream csv(dir / "servo.csv");
    csv << "mode,rate_hz,period_p50_us,period_p99_us,p99_ratio_to_bare,period_max_us,overruns,"
           "allocations_in_loop,"
           "udp_unanswered,realtime\n";
    for (const ModeResult& r : results) {
      csv << r.name << "," << r.stats.rate_hz << "," << r.stats.period_p50_us << ","
          << r.stats.period_p99_us << "," << ratio(r) << "," << r.stats.period_max_us << ","
          << r.stats.overruns << "," << r.allocations << "," << r.udp_unanswered << ","
          << (r.stats.realtime ? 1 : 0) << "\n";
    }
    std::ofstream hist(dir / "servo_periods.csv");
    hist << "period_us";
    for (const ModeResult& r : results) hist << "," << r.name;
    hist << "\n";
    for (size_t b = 0; b < results[0].histogram.size(); ++b) {
      bool any = false;
      for (const ModeResult& r : results) any |= r.histogram[b] > 0;
      if (!any) continue;
      hist << (b + 1) * 10;
      for (const ModeResult& r : results) hist << "," << r.histogram[b];
      hist << "\n";
    }
  }
  std::vector<Series> series;
  for (const ModeResult& r : results) {
    Series s{r.name, {}, {}};
    for (size_t b = 80; b < 120 && b < r.histogram.size(); ++b) {  // 800..1200 µs
      s.x.push_back(static_cast<double>(b * 10 + 5));
      s.y.push_back(r.histogram[b]);
    }
    series.push_back(s);
  }
  PlotLines(dir / "servo_periods.png", series,
            {"servo period histogram (10 us bins, 800-1200 us)", "period, us", "cycles", true});
  std::printf("\n  wrote %s, %s, %s\n", (dir / "servo.csv").c_str(),
              (dir / "servo_periods.csv").c_str(), (dir / "servo_periods.png").c_str());

  if (json) {
    std::ostringstream o;
    o << "{\"modes\":{";
    double udp_two_arms_hz = 0.0;
    for (size_t i = 0; i < results.size(); ++i) {
      o << (i ? "," : "") << "\"" << results[i].name << "\":" << Json(results[i], bare_p99);
      if (results[i].name == "udp_two_arms_decimated") udp_two_arms_hz = results[i].stats.rate_hz;
    }
    o << "},\"rate_hz_udp_two_arms\":" << udp_two_arms_hz << ",\"seconds_per_mode\":" << seconds
      << "}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
