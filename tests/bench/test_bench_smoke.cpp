// Every benchmark's smoke run (`haptel-bench NAME --smoke --json`), as a
// program of its own: it exits 0, ends with one JSON line that says it is a
// smoke run, writes its table and files, and its figures are the kind the full
// run reports (finite numbers, the lists it promises, the checks it makes).
// So a benchmark can no longer rot unnoticed. Behaviour only: no figure is
// held to a time.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "child.hpp"
#include "json_value.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using haptel::test::Child;
using haptel::test::JsonValue;

namespace {

/// How long one benchmark may take before the test gives up on it: a bound
/// on a hang, far above any smoke run (seconds each); not a timing check.
constexpr double kHangBound_s = 300.0;

fs::path Bin(const std::string& name) {
  static const fs::path dir = fs::absolute(haptel::test::BinDir());
  return dir / name;
}

/// The benchmarks run in a scratch folder of their own, so their files
/// (build/bench/smoke/ under the working directory) land there, not in a
/// build tree. Shipped configs still resolve (ShippedFile falls back to
/// the source tree).
const fs::path& WorkDir() {
  static const fs::path dir = [] {
    Bin("");  // resolved before the working directory changes
    const fs::path d = haptel::test::ScratchDir("bench-smoke");
    if (::chdir(d.c_str()) != 0) throw std::runtime_error("cannot enter " + d.string());
    return d;
  }();
  return dir;
}

fs::path SmokeDir() { return WorkDir() / "build" / "bench" / "smoke"; }

struct SmokeRun {
  std::string out;
  JsonValue json;
};

/// Waits for `child`, started with `argv` (a program and its arguments), to
/// end; requires exit code 0 and a last stdout line that is a JSON object
/// with "smoke":true.
SmokeRun Finish(Child& child, const std::vector<std::string>& argv) {
  int code = child.Wait(kHangBound_s);
  if (code == Child::kRunning) {
    child.Terminate();
    FAIL_CHECK(argv[0] << " " << argv[1] << " still ran after " << kHangBound_s
                       << " s (a hang): terminated");
  }
  INFO("stdout:\n" << child.out() << "\nstderr:\n" << child.err());
  REQUIRE(code == 0);
  const std::string last = child.LastLine();
  INFO("last line: " << last);
  JsonValue json;
  REQUIRE_NOTHROW(json = JsonValue::Parse(last));
  REQUIRE(json.is_object());
  REQUIRE(json.has("smoke"));
  CHECK(json["smoke"].boolean());
  // The table says so too, first.
  CHECK_THAT(child.out(), Catch::Contains("SMOKE run (--smoke)"));
  return {child.out(), json};
}

/// Runs `argv` to its end, as Finish checks it.
SmokeRun RunToEnd(const std::vector<std::string>& argv) {
  WorkDir();
  Child child(argv);
  return Finish(child, argv);
}

/// `haptel-bench NAME --smoke --json` plus `extra`.
SmokeRun Smoke(const std::string& name, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{Bin("haptel-bench").string(), name, "--smoke", "--json"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return RunToEnd(argv);
}

/// A number that is finite (JsonNumber writes null for NaN and infinities,
/// which number() refuses).
double Finite(const JsonValue& v) {
  const double x = v.number();
  CHECK(std::isfinite(x));
  return x;
}

void RequireFiles(const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    INFO("file " << (SmokeDir() / name));
    CHECK(fs::is_regular_file(SmokeDir() / name));
    CHECK(fs::file_size(SmokeDir() / name) > 0);
  }
}

}  // namespace

TEST_CASE("JsonValue reads what the benchmarks write and refuses what is not JSON",
          "[bench][smoke]") {
  const JsonValue v = JsonValue::Parse(R"({"a":[1,-2.5e-3,{"b":null}],"c":"x\"y","d":true} )");
  CHECK(v["a"].array().size() == 3);
  CHECK(v["a"][1].number() == Approx(-0.0025));
  CHECK(v["a"][2]["b"].kind() == JsonValue::Kind::kNull);
  CHECK(v["c"].string() == "x\"y");
  CHECK(v["d"].boolean());
  CHECK_THROWS(v["e"]);
  CHECK_THROWS(v["c"].number());
  for (const char* bad :
       {R"({"a":nan})", R"({"a":1,})", R"({"a":1 "b":2})", R"({"a":1}x)", R"({a:1})", R"({"a":01})",
        R"({"a":1.})", R"([1,2)", R"({"a":inf})", ""}) {
    INFO(bad);
    CHECK_THROWS(JsonValue::Parse(bad));
  }
}

TEST_CASE("bench servo --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("servo").json;
  CHECK(j["seconds_per_mode"].number() == 0.5);
  const std::set<std::string> expected{"bare_clock_nanosleep", "local_one_arm", "local_two_arms",
                                       "udp_two_arms_decimated", "udp_two_arms_every_cycle"};
  std::set<std::string> modes;
  for (const auto& [name, mode] : j["modes"].object()) {
    INFO(name);
    modes.insert(name);
    CHECK(Finite(mode["rate_hz"]) > 0.0);
    const double p50 = Finite(mode["period_p50_us"]);
    CHECK(p50 > 0.0);
    CHECK(Finite(mode["period_p99_us"]) >= p50);
    CHECK(Finite(mode["p99_ratio_to_bare"]) > 0.0);
  }
  CHECK(modes == expected);
  CHECK(Finite(j["rate_hz_udp_two_arms"]) > 0.0);
  RequireFiles({"servo.csv", "servo_periods.csv", "servo_periods.png"});
}

TEST_CASE("bench gravity --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("gravity").json;
  CHECK(j["vertices"].number() == 8);  // 2 x 2 x 2
  CHECK(j["points"].number() == 3);
  CHECK(Finite(j["sampling_sim_s"]) > 0.0);
  // Off, the arm falls; on, it drifts less.
  const double off = Finite(j["drift_mean_off_mm_s"]);
  const double on = Finite(j["drift_mean_on_mm_s"]);
  CHECK(off > 0.0);
  CHECK(on >= 0.0);
  CHECK(on < off);
  CHECK(Finite(j["drift_ratio"]) > 1.0);
  CHECK(Finite(j["force_error_max_n"]) >= 0.0);
  RequireFiles({"gravity.csv", "gravity_vertices.csv", "gravity.png", "gravity_grid.yaml"});
}

TEST_CASE("bench skip --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("skip").json;
  const JsonValue& cpu = j["cpu_per_sim_s"];
  CHECK(cpu["gesture"].number() == 0.0);  // no world at all
  // A smoke run's floor has 10 and 100 boxes (the full run's 100 and 1000).
  for (const char* world :
       {"cockpit", "cockpit_sleeping_0", "cockpit_sleeping_10", "cockpit_sleeping_100"}) {
    INFO(world);
    CHECK(Finite(cpu[world]) > 0.0);
  }
  CHECK(cpu.object().size() == 5);
  CHECK(Finite(j["cpu_per_sim_s_static_100"]) > 0.0);
  CHECK(j["video_decode_cpu_share"]["view_none"].number() == 0.0);  // not decoded
  CHECK(Finite(j["video_decode_cpu_share"]["view"]) > 0.0);
  const JsonValue& camera = j["vehicle_camera"];
  CHECK(camera["width"].number() > 0);
  CHECK(camera["height"].number() > 0);
  CHECK(Finite(camera["cpu_share"]) > 0.0);
  RequireFiles({"skip.csv", "skip_camera.csv"});
}

TEST_CASE("bench physics --smoke: the fine reference, both precisions", "[bench][smoke]") {
  // The reference run steps at 0.025 ms, finer than a physics file may ask:
  // this run failed on that check before the reference had a path of its own.
  const JsonValue j = Smoke("physics").json;
  int doubles = 0, floats = 0;
  for (const JsonValue& p : j["points"].array()) {
    const std::string precision = p["precision"].string();
    INFO(precision << " " << p["step_ms"].number() << " ms, " << p["iterations"].number()
                   << " iterations");
    (precision == "float" ? floats : doubles) += 1;
    CHECK((precision == "double" || precision == "float"));
    CHECK(Finite(p["cpu_per_sim_s"]) > 0.0);
    CHECK(Finite(p["tracking_err_mm"]) >= 0.0);
    CHECK(Finite(p["penetration_mm"]) >= 0.0);
    CHECK(Finite(p["slip_mm"]) >= 0.0);
  }
  // 2 steps x 2 iteration counts each; the float ones from haptel-physics-bench-float.
  CHECK(doubles == 4);
  CHECK(floats == 4);
  const JsonValue& def = j["default"];
  CHECK(def["step_ms"].number() == 1.0);
  CHECK(def["iterations"].number() == 20);
  CHECK(def["precision"].string() == "double");
  CHECK(Finite(def["tracking_err_mm"]) > 0.0);  // a 1 ms step is not the 0.025 ms reference
  CHECK_FALSE(j["pareto"].array().empty());
  CHECK(Finite(j["default_error_ratio"]) > 0.0);
  CHECK(Finite(j["default_cpu_ratio"]) > 0.0);
  RequireFiles({"physics.csv", "physics_pareto.png", "trajectory.csv", "physics_reference.csv"});
}

TEST_CASE("bench stability --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("stability").json;
  CHECK(j["passed"].boolean());
  const JsonValue& t = j["tests"];
  const auto& steps = t["stiffness"]["steps"].array();
  CHECK(steps.size() == 2);
  for (const JsonValue& s : steps) CHECK(Finite(s["k_max"]) > 0.0);
  const auto& ratios = t["mass_ratio"]["ratios"].array();
  CHECK(ratios.size() == 4);
  for (const JsonValue& r : ratios) {
    CHECK(r["resets"].number() == 0);
    CHECK(r["on_box"].boolean());
  }
  CHECK(t["squash"]["passed"].boolean());
  CHECK(Finite(t["squash"]["contact_force_mean_n"]) > 0.0);
  const JsonValue& grasp = t["grasp_release"];
  CHECK(grasp["cycles"].number() == 2);
  CHECK(grasp["lifted"].number() == 2);
  CHECK(grasp["resets"].number() == 0);
  RequireFiles({"stability_stiffness.csv", "stability_mass_ratio.csv", "stability_squash.csv",
                "stability_grasp_release.csv", "stability_stiffness.png"});
}

TEST_CASE("bench passivity --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("passivity").json;
  CHECK(Finite(j["passivity_bound"]) > 0.0);
  CHECK(Finite(j["stable_stiffness_off"]) >= 0.0);
  CHECK(Finite(j["stable_stiffness_on"]) >= 0.0);
  CHECK(Finite(j["stable_stiffness_two_port"]) >= 0.0);
  CHECK(Finite(j["cost_us_p99"]) >= 0.0);
  CHECK(!j["gain_mode"].string().empty());
  // The servo loop's own period p99, off and on, beside the bare loop's.
  for (const char* key :
       {"servo_p99_us_bare", "servo_p99_us_off", "servo_p99_us_on", "servo_p99_tolerance_us"}) {
    INFO(key);
    CHECK(Finite(j[key]) > 0.0);
  }
  CHECK(Finite(j["servo_p99_spread_us_bare"]) >= 0.0);
  CHECK(j["servo_p99_tolerance_us"].number() >= j["servo_p99_spread_us_bare"].number());
  CHECK(j["servo_p99_unchanged"].boolean() ==
        (std::abs(j["servo_p99_us_on"].number() - j["servo_p99_us_off"].number()) <=
         j["servo_p99_tolerance_us"].number()));
  CHECK(j["servo_allocations_on"].number() == 0);  // the controller allocates nothing in the loop
  const auto& points = j["points"].array();
  // 2 delays x 7 modes (off, one-port, two-port, two-port-ref; over the UDP device:
  // udp-off, udp-two-port, udp-2p-admit) x 3 stiffnesses
  CHECK(points.size() == 42);
  for (const char* key : {"stable_stiffness_udp_off", "stable_stiffness_udp_two_port", "gain_udp",
                          "gain_udp_admittance"}) {
    INFO(key);
    CHECK(Finite(j[key]) >= 0.0);
  }
  for (const JsonValue& p : points) {
    CHECK(Finite(p["force_rms_err_n"]) >= 0.0);
    CHECK(Finite(p["energy_j"]) >= 0.0);
  }
  // The grasped box: the same sweep, its own figures.
  const JsonValue& box = j["box"];
  CHECK(Finite(box["mass_kg"]) > 0.0);
  for (const char* key :
       {"stable_stiffness_off", "stable_stiffness_two_port", "stable_stiffness_udp_two_port",
        "gain", "gain_udp", "force_rms_err_n_off"}) {
    INFO("box " << key);
    CHECK(Finite(box[key]) >= 0.0);
  }
  CHECK(box["points"].array().size() == points.size());
  for (const JsonValue& p : box["points"].array()) CHECK(Finite(p["force_rms_err_n"]) >= 0.0);
  RequireFiles({"passivity.csv", "passivity.png", "passivity_box.csv"});
}

TEST_CASE("bench view --smoke", "[bench][smoke]") {
  // Offscreen, whatever display the suite has; the vehicle on a domain of its own.
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  const JsonValue j =
      Smoke("view", {"--domain", std::to_string(haptel::test::UniqueDomain(81))}).json;
  CHECK(j["mode"].string() == "offscreen");
  CHECK(Finite(j["view_fps"]) > 0.0);
  CHECK(Finite(j["view_frame_ms_p50"]) > 0.0);
  CHECK(Finite(j["video_to_screen_ms_p50"]) > 0.0);  // the vehicle's video reached the screen
  for (const char* phase : {"servo_p99_us_bare", "servo_p99_us_world", "servo_p99_us_view"}) {
    INFO(phase);
    CHECK(Finite(j[phase]) > 0.0);
  }
  CHECK(j["record"]["recorded_frames"].number() > 0);
  RequireFiles({"view.csv", "view.png", "view-bench.mp4"});
}

TEST_CASE("bench blimp --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("blimp").json;
  CHECK(j["passed"].boolean());
  CHECK_FALSE(j["default"]["integrator"].string().empty());
  const auto& sweep = j["sweep"].array();
  CHECK(sweep.size() == 21);  // 3 integrators x 7 steps
  for (const JsonValue& row : sweep) {
    CHECK(row["finite"].boolean());
    CHECK(Finite(row["error_m"]) >= 0.0);
    CHECK(Finite(row["cpu_ms_per_sim_s"]) > 0.0);
  }
  const JsonValue& checks = j["checks"];
  CHECK(checks["no_nan"].boolean());
  CHECK(Finite(checks["top_speed_kmh"]) > 0.0);
  CHECK(Finite(checks["hover_drift_m"]) >= 0.0);
  RequireFiles({"blimp_precision.csv", "blimp_checks.csv", "blimp_precision.png"});
}

TEST_CASE("bench link --smoke; beside it, --rtt-only: the round trips alone, no lap",
          "[bench][smoke][network]") {
  // --rtt-only in a folder of its own (its files are the full smoke's
  // names), so its round trips overlap the full smoke's instead of
  // following it.
  const fs::path rtt_only_dir = WorkDir() / "rtt-only";
  fs::create_directories(rtt_only_dir);
  const std::vector<std::string> rtt_only_argv{"/usr/bin/env",
                                               "-C",
                                               rtt_only_dir.string(),
                                               Bin("haptel-bench").string(),
                                               "link",
                                               "--smoke",
                                               "--json",
                                               "--rtt-only",
                                               "--domain",
                                               std::to_string(haptel::test::UniqueDomain(85))};
  Child rtt_only(rtt_only_argv);
  const JsonValue j =
      Smoke("link", {"--domain", std::to_string(haptel::test::UniqueDomain(82)), "--lap-domain",
                     std::to_string(haptel::test::UniqueDomain(83))})
          .json;
  const JsonValue& rtt = j["rtt"];
  for (const char* key : {"raw_p50_ms", "haptel_p50_ms", "secured_p50_ms"}) {
    INFO(key);
    CHECK(Finite(rtt[key]) > 0.0);
  }
  CHECK(Finite(rtt["video_p50_ms"]) > 0.0);
  CHECK(Finite(rtt["secured_video_p50_ms"]) > 0.0);
  // The tail beside the median, and where the round trip goes: out and back.
  for (const char* key : {"raw_p99_ms", "haptel_p99_ms", "p99_ratio", "out_p50_ms", "out_p99_ms",
                          "back_p50_ms", "back_p99_ms"}) {
    INFO(key);
    CHECK(Finite(rtt[key]) > 0.0);
  }
  CHECK(Finite(rtt["out_p50_ms"]) <= Finite(rtt["out_p99_ms"]));
  CHECK(Finite(rtt["back_p50_ms"]) <= Finite(rtt["back_p99_ms"]));
  const auto& laps = j["laps"].array();
  REQUIRE(laps.size() ==
          1);  // one learning lap of the twin (`none`): no delay or loss, short track
  const JsonValue& lap = laps[0];
  CHECK(lap["vehicle"].string() == "robot");
  CHECK(lap["completed"].boolean());
  CHECK(lap["outcome"].string() == "completed");
  CHECK(lap["predict"].boolean());
  CHECK(lap["mode"].string() == "learn");
  // The reality as the vehicle's truth record names it, and the prediction scored against it.
  CHECK(lap["reality"]["name"].string() == "none");
  CHECK(Finite(lap["reality"]["seed"]) >= 0.0);
  // The twin is the model the operator predicts with: centimetres at most against the truth.
  CHECK(Finite(lap["prediction_error_m_p95"]) < 0.05);
  CHECK(Finite(lap["prediction_error_m_p95"]) >= Finite(lap["prediction_error_m_p50"]));
  CHECK(Finite(lap["prediction_error_odometry_m_p95"]) >= 0.0);
  CHECK(Finite(lap["lap_time_s"]) > 0.0);
  // What the predictor estimated, each beside the truth the vehicle drew.
  REQUIRE_FALSE(lap["estimated"].object().empty());
  for (const auto& [param, e] : lap["estimated"].object()) {
    INFO(param);
    CHECK(std::isfinite(e["estimate"].number()));
    CHECK(Finite(e["truth"]) > 0.0);
  }
  CHECK(lap["path_gap_m_max"].kind() ==
        JsonValue::Kind::kNull);  // no twin's lap (`none`) to compare with
  // The targets need the 400 ms lap and the other realities: not measured here.
  CHECK(j["targets"]["lab_ratio_met"].kind() == JsonValue::Kind::kNull);
  CHECK(j["targets"]["harsh_learn_beats_nominal"].kind() == JsonValue::Kind::kNull);
  RequireFiles({"link_rtt.csv", "link_laps.csv", "link_estimates.csv", "link_laps.png",
                "link_laps_error.png", "link_truth/robot-none-learn-0ms-0pc.csv"});

  INFO("--rtt-only");
  const JsonValue r = Finish(rtt_only, rtt_only_argv).json;
  CHECK(Finite(r["rtt"]["haptel_p99_ms"]) > 0.0);
  CHECK(Finite(r["rtt"]["raw_p99_ms"]) > 0.0);
  CHECK(r["laps"].array().empty());
}

TEST_CASE(
    "bench link --smoke over seeds, in simulated time: each cell's spread, learning "
    "against nominal seed by seed",
    "[bench][smoke][network]") {
  // harsh on the short track, seeds 1 and 2, nominal and learning at 0 ms:
  // four laps of a second or less each (simulated time), beside the round trips.
  const JsonValue j =
      Smoke("link", {"--domain", std::to_string(haptel::test::UniqueDomain(86)), "--reality",
                     "harsh", "--predict", "nominal,learn", "--seeds", "1-2", "--simulated-time"})
          .json;
  CHECK(j["simulated_time"].boolean());
  REQUIRE(j["seeds"].array().size() == 2);
  const auto& laps = j["laps"].array();
  REQUIRE(laps.size() == 4);
  // Each seed's learn − nominal lap, by hand from the laps.
  double lap[2][2] = {};  // [mode: nominal, learn][seed 1, 2]
  for (const JsonValue& l : laps) {
    CHECK(l["reality"]["name"].string() == "harsh");
    const int seed = static_cast<int>(Finite(l["reality"]["seed"]));
    REQUIRE((seed == 1 || seed == 2));
    REQUIRE(l["completed"].boolean());
    lap[l["mode"].string() == "learn" ? 1 : 0][seed - 1] = Finite(l["lap_time_s"]);
  }
  const auto& cells = j["cells"].array();
  REQUIRE(cells.size() == 2);  // nominal and learning at 0 ms
  for (const JsonValue& c : cells) {
    const int m = c["mode"].string() == "learn" ? 1 : 0;
    CHECK(Finite(c["laps"]) == 2);
    CHECK(Finite(c["lap_time_s"]["n"]) == 2);
    CHECK(Finite(c["lap_time_s"]["mean"]) == Approx(0.5 * (lap[m][0] + lap[m][1])));
    CHECK(Finite(c["lap_time_s"]["sd"]) ==
          Approx(std::abs(lap[m][0] - lap[m][1]) / std::sqrt(2.0)).margin(1e-9));
  }
  const auto& paired = j["learn_minus_nominal"].array();
  REQUIRE(paired.size() == 2);  // the lap and the error p95 at 0 ms
  const JsonValue& d = paired[0];
  CHECK(d["figure"].string() == "lap_time_s");
  const double d1 = lap[1][0] - lap[0][0], d2 = lap[1][1] - lap[0][1];
  CHECK(Finite(d["difference"]["mean"]) == Approx(0.5 * (d1 + d2)).margin(1e-9));
  // Two seeds: t(0.975, 1) = 12.706, the interval ± 12.706 × sd / √2.
  const double half = 12.7062 * std::abs(d1 - d2) / std::sqrt(2.0) / std::sqrt(2.0);
  CHECK(Finite(d["difference"]["ci95"].array()[1]) - Finite(d["difference"]["mean"]) ==
        Approx(half).margin(1e-3));
  CHECK(j["targets"]["harsh_learn_better_every_cell"].kind() == JsonValue::Kind::kBool);
}

TEST_CASE("bench fleet --smoke: the fewest and the most vehicles, each count's figures",
          "[bench][smoke][network]") {
  const JsonValue j =
      Smoke("fleet", {"--domain", std::to_string(haptel::test::UniqueDomain(84))}).json;
  const auto& counts = j["counts"].array();
  REQUIRE(counts.size() == 2);  // 1 and 4 of config/fleets/four.yaml
  CHECK(counts[0]["vehicles"].number() == 1);
  CHECK(counts[1]["vehicles"].number() == 4);
  for (const JsonValue& c : counts) {
    INFO("vehicles " << c["vehicles"].number());
    CHECK(c["ran"].boolean());
    CHECK(Finite(c["operator_cpu_share"]) > 0.0);
    CHECK(Finite(c["servo_p99_us"]) > 0.0);
    CHECK(Finite(c["bare_alone_p99_us"]) > 0.0);
    CHECK(Finite(c["bare_beside_p99_us"]) > 0.0);
  }
  CHECK(counts[0]["handovers"].number() == 0);  // one vehicle: nothing to switch to
  CHECK_NOTHROW(Finite(counts[1]["cpu_added_per_vehicle"]));
  // The handover and the cue's ticks at 4 depend on how soon the vehicles
  // answer within the smoke's 6 s: present, not held to a count.
  CHECK(counts[1]["servo_cue_ticks"].number() >= 0);
  CHECK(Finite(j["servo_p99_us_bare"]) > 0.0);
  CHECK(Finite(j["servo_p99_us_fleet"]) > 0.0);
  CHECK_NOTHROW(j["handover_ms_p95_at_4"]);
  CHECK_NOTHROW(j["servo_unchanged"].boolean());
  // The video (issue 40): each vehicle's, the first on the big screen at
  // the camera's size, the others tiles at a preview's (half of it).
  const auto& video = j["video"]["counts"].array();
  REQUIRE(video.size() == 2);
  for (const JsonValue& c : video) {
    INFO("video of " << c["vehicles"].number() << " vehicle(s): " << c["error"].string());
    CHECK(c["ran"].boolean());
    const auto& vehicles = c["vehicle"].array();
    REQUIRE(vehicles.size() == static_cast<size_t>(c["vehicles"].number()));
    CHECK(vehicles[0]["shown"].string() == "screen");
    CHECK(vehicles[0]["width"].number() == 640);
    for (const JsonValue& v : vehicles) {
      INFO(v["name"].string());
      CHECK(Finite(v["kbps"]) > 0.0);
      CHECK(Finite(v["fps"]) > 0.0);
      CHECK(Finite(v["target_kbps"]) > 0.0);
      if (v["shown"].string() == "tile") CHECK(v["width"].number() == 320);
    }
  }
  RequireFiles({"fleet.csv", "fleet.png", "fleet_video.csv"});
}

TEST_CASE("bench fuzz --smoke", "[bench][smoke]") {
  const JsonValue j = Smoke("fuzz").json;
  CHECK(j["crashes"].number() == 0);
  CHECK(j["hangs"].number() == 0);
  std::vector<std::string> targets;
  for (const JsonValue& t : j["targets"].array()) {
    targets.push_back(t["target"].string());
    INFO(targets.back());
    const double inputs = t["inputs"].number();
    CHECK(inputs == 300);
    CHECK(t["accepted"].number() + t["rejected"].number() == inputs);
    CHECK(t["accepted"].number() > 0);  // every 64th input is a valid seed
    // The console's page under 100 slow connections: answered (200), not
    // counted as its 10-s limit; how fast is the bench's figure, not a check.
    if (targets.back() == "console") CHECK(t["page_under_slow_clients_ms"].number() < 10000.0);
  }
  CHECK(targets ==
        std::vector<std::string>{"config", "scene", "udp", "servo", "can", "dds", "console"});
  RequireFiles({"fuzz.csv"});
}

TEST_CASE("bench soak --smoke: one kill of each kind, each followed by its checks; nothing lost",
          "[bench][smoke]") {
  const JsonValue j =
      Smoke("soak", {"--domain", std::to_string(haptel::test::UniqueDomain(85))}).json;
  for (const char* kind : {"study", "run", "reader"}) {
    INFO(kind);
    CHECK(j["kills"][kind].number() >= 1);
  }
  // A check after every kill, and one at the end; every one passed.
  CHECK(j["integrity_checks"].number() == j["kills_total"].number() + 1);
  CHECK(j["integrity_passed"].number() == j["integrity_checks"].number());
  CHECK(j["study_resumes"].number() >= 1);
  // Rows of each kind acknowledged, and every one found.
  CHECK(j["rows_acknowledged_by_kind"]["participants"].number() > 0);
  CHECK(j["rows_acknowledged_by_kind"]["runs"].number() > 0);
  CHECK(j["rows_found"].number() == j["rows_acknowledged"].number());
  CHECK(j["rows_lost"].number() == 0);
  CHECK(j["checks_missing_rows"].number() == 0);
  CHECK(j["ok"].boolean());
  RequireFiles({"soak.csv"});
}

TEST_CASE("bench video --smoke", "[bench][smoke][network]") {
  const JsonValue j = Smoke("video").json;
  const auto& codecs = j["codecs"].array();
  REQUIRE(codecs.size() >= 4);  // JPEG at 20 and 80, H.264 at 250 and 2000 kbit/s (and the default)
  bool any_jpeg = false, any_h264 = false, any_front = false;
  for (const JsonValue& c : codecs) {
    const std::string codec = c["codec"].string();
    any_jpeg = any_jpeg || codec == "jpeg";
    any_h264 = any_h264 || codec == "h264";
    any_front = any_front || c["pareto"].boolean();
    CHECK(Finite(c["setting"]) > 0.0);
    CHECK(Finite(c["bitrate_kbps"]) > 0.0);
    CHECK(Finite(c["ssim"]) > 0.5);
    CHECK(Finite(c["ssim"]) <= 1.0);
    CHECK(Finite(c["psnr_db"]) > 10.0);
    CHECK(Finite(c["encode_ms"]) >= 0.0);
    CHECK(Finite(c["decode_ms"]) >= 0.0);
  }
  CHECK(any_jpeg);
  CHECK(any_h264);
  CHECK(any_front);
  CHECK_FALSE(j["default"]["codec"].string().empty());
  CHECK(Finite(j["default"]["setting"]) > 0.0);
  CHECK_NOTHROW(j["default"]["on_pareto_front"].boolean());
  // Part 2: the capacity schedule, five short phases of the default codec through a real vehicle.
  const auto& schedule = j["schedule"].array();
  REQUIRE(schedule.size() == 5);
  const std::vector<double> capacities{2000, 1000, 1750, 500, 1000};
  for (size_t i = 0; i < schedule.size(); ++i) {
    const JsonValue& p = schedule[i];
    CHECK(p["codec"].string() == j["default"]["codec"].string());
    CHECK(p["capacity_kbps"].number() == capacities[i]);
    CHECK(Finite(p["video_kbps"]) > 0.0);  // video came through in every phase
    CHECK(Finite(p["latency_ms_p50"]) > 0.0);
    CHECK(Finite(p["latency_ms_p95"]) >= p["latency_ms_p50"].number());
    CHECK(Finite(p["stale_s"]) >= 0.0);
    CHECK(Finite(p["command_rtt_ms_p99"]) > 0.0);
    CHECK(p["frames_lost"].number() >= 0.0);
  }
  CHECK(Finite(j["adapt_s"]) >= 0.0);
  // Part 3 (issue 38): the blimp's two cameras sharing the link, two short phases.
  const auto& cameras = j["cameras"].array();
  REQUIRE(cameras.size() == 4);  // pilot and surveillance per phase
  for (const JsonValue& c : cameras) {
    INFO(c["camera"].string() << " at " << c["capacity_kbps"].number() << " kbit/s");
    CHECK(Finite(c["fps"]) > 0.0);  // each camera's pictures came in every phase
    CHECK(Finite(c["kbps"]) > 0.0);
    CHECK(Finite(c["latency_ms_p95"]) >= c["latency_ms_p50"].number());
  }
  CHECK(cameras[0]["camera"].string() == "pilot");
  CHECK(cameras[1]["camera"].string() == "surveillance");
  CHECK(j["aims_shown"].number() > 0.0);  // a re-aimed camera's picture showed its command
  CHECK(Finite(j["aim_latency_ms_p95"]) >= j["aim_latency_ms_p50"].number());
  RequireFiles({"video_codecs.csv", "video_codecs.png",
                "video_schedule_" + j["default"]["codec"].string() + ".csv",
                "video_schedule_" + j["default"]["codec"].string() + ".png", "video_cameras.csv",
                "video_cameras_trace.csv", "video_cameras.png"});
}

TEST_CASE("bench record --smoke: two laps, without and with a session file, and a seek",
          "[bench][smoke][network]") {
  const JsonValue j =
      Smoke("record", {"--domain", std::to_string(haptel::test::UniqueDomain(86))}).json;
  CHECK(j["saved"].boolean());
  CHECK(j["dropped"].number() == 0);  // behaviour: the rings keep up with a short lap
  CHECK(Finite(j["cpu_share"]) > 0.0);
  CHECK(Finite(j["bytes_per_minute"]) > 0.0);
  CHECK(Finite(j["servo_p99_us_bare_run"]) > 0.0);
  CHECK(Finite(j["servo_p99_us_recorded_run"]) > 0.0);
  CHECK(Finite(j["seek_open_ms"]) >= 0.0);
  CHECK(j["session_file"]["channels"].array().size() >= 5);
  RequireFiles({"record.csv", "record-lap.mcap"});
}

TEST_CASE("bench hands --smoke: the gesture interface through the real window, engaged and not",
          "[bench][smoke][hands]") {
  const JsonValue j = Smoke("hands").json;
  REQUIRE(j["interfaces"].array().size() == 1);
  const JsonValue& g = j["interfaces"][0];
  INFO("error: " << g["error"].string());
  CHECK(g["interface"].string() == "gesture");
  CHECK(g["ran"].boolean());
  CHECK(g["commands"].number() > 0);
  CHECK(g["steps"].number() == 4);  // each step, up to the next (the last, to the push)
  CHECK(Finite(g["ratio_free"]) >= 0.0);
  CHECK(Finite(g["servo_p99_us"]) > 0.0);
  CHECK(Finite(g["bare_alone_p99_us"]) > 0.0);
  CHECK(Finite(g["bare_beside_p99_us"]) > 0.0);
  CHECK(g["nobody_commands"].number() > 0);
  // Nobody engaged: no command that moves the vehicle (behaviour, not a figure).
  CHECK(g["nobody_moving_commands"].number() == 0);
  CHECK_NOTHROW(j["input_to_command_target_met"].boolean());
  CHECK_NOTHROW(j["servo_unchanged"].boolean());
  RequireFiles({"hands.csv", "hands.png"});
}

TEST_CASE("haptel bench NAME --smoke through the haptel program; every usage line offers --smoke",
          "[bench][smoke]") {
  const JsonValue j =
      RunToEnd({Bin("haptel").string(), "bench", "fuzz", "--target", "udp", "--smoke", "--json"})
          .json;
  REQUIRE(j["targets"].array().size() == 1);
  CHECK(j["targets"][0]["inputs"].number() == 300);

  Child help({Bin("haptel").string(), "bench", "--help"});
  REQUIRE(help.Wait(60.0) == 0);
  std::istringstream lines(help.out());
  int benches = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  haptel bench ", 0) != 0) continue;
    INFO(line);
    ++benches;
    CHECK_THAT(line, Catch::Contains("[--smoke]"));
  }
  CHECK(benches == 15);  // record (issue 37) the newest
}
