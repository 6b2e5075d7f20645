// haptel-bench: the benchmarks, a program of their own so that the product
// (`haptel`) links neither them nor the allocation counter they use (its
// global operator new would tax every allocation of a run). `haptel bench
// NAME ...` execs this program.
#include <cstdio>
#include <string>

#include "blimp_bench.hpp"
#include "fleet_bench.hpp"
#include "fuzz_bench.hpp"
#include "gravity_bench.hpp"
#include "hands_bench.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "link_bench.hpp"
#include "passivity_bench.hpp"
#include "physics_bench.hpp"
#include "record_bench.hpp"
#include "servo_bench.hpp"
#include "skip_bench.hpp"
#include "soak_bench.hpp"
#include "stability_bench.hpp"
#include "video_bench.hpp"
#include "view_bench.hpp"

using namespace haptel::bench;

#ifndef HAPTEL_BENCH_HANDS
// Built without libXtst (a test package): the benchmark says what it needs.
int haptel::bench::BenchHandsMain(int /*argc*/, const char* const* /*argv*/) {
  std::fprintf(stderr,
               "haptel bench hands: not built: it moves the X pointer through libXtst (Debian: "
               "libxtst-dev, which scripts/test installs); install it and rebuild\n");
  return 1;
}
#endif

namespace {

/// Each benchmark's options, for --help (what its own parser accepts).
struct Usage {
  const char* name;
  const char* options;
  const char* what;
};
constexpr Usage kUsage[] = {
    {"servo", "[--seconds S] [--device FILE] [--smoke] [--json]",
     "servo loop modes against an empty clock_nanosleep loop"},
    {"gravity",
     "[--device FILE] [--points N] [--counts N] [--seed S] [--grid-out FILE] [--smoke] [--json]",
     "gravity compensation: drift with it off and on"},
    {"skip", "[--physics FILE] [--seconds S] [--smoke] [--json]",
     "physics CPU per simulated second; what a scene skips"},
    {"physics", "[--physics FILE] [--no-float] [--smoke] [--json]",
     "work-precision: step x iterations x float/double"},
    {"stability", "[--physics FILE] [--minutes M] [--smoke] [--json]", "physics stress tests"},
    {"passivity", "[--device FILE] [--smoke] [--json]",
     "the servo loop's passivity controller: largest stable wall stiffness against device delay, "
     "off and on"},
    {"view", "[--seconds S] [--domain D] [--smoke] [--json]",
     "the operator's view: frame rate, CPU, video-to-screen, servo beside it"},
    {"blimp", "[--vehicle FILE] [--smoke] [--json]",
     "airship model: integrators x steps, error against CPU; physics checks"},
    {"link",
     "[--seconds S] [--vehicles robot,blimp] [--track FILE] [--blimp-track FILE] [--reality "
     "NAME,...] [--seeds 1-5] [--delays MS,...] [--losses PERCENT,...] [--predict "
     "off,nominal,learn] [--link-profile NAME] [--simulated-time] [--domain D] [--lap-domain D] "
     "[--rtt-only] [--smoke] [--json]",
     "DDS round trip against raw Fast DDS; the lap against the link's delay per reality, "
     "prediction off, nominal and learning, its error against the truth; over seeds, each "
     "cell's spread and learning against nominal seed by seed"},
    {"video",
     "[--vehicle FILE] [--track FILE] [--schedule default|both|jpeg|h264|off] [--phase-s S] "
     "[--cameras FILE|off] [--cameras-only] [--domain D] [--smoke] [--json]",
     "the link's video codecs: JPEG qualities and H.264 bitrates against SSIM, PSNR and CPU; the "
     "Pareto front; "
     "then a capacity schedule through a real vehicle (bitrate, SSIM, latency, adapt_s); then two "
     "cameras sharing the link (fps, kbit/s, share, latency, pan/tilt/zoom to picture)"},
    {"fuzz", "[--inputs N] [--target NAME] [--seed S] [--smoke] [--json]",
     "every parser fed 10^6 mutated inputs: configs, scenes, UDP, servo bytes, CAN, DDS samples, "
     "console HTTP"},
    {"fleet",
     "[--fleet FILE] [--counts LIST] [--slice S] [--time-limit S] [--device FILE] [--domain D] "
     "[--video-seconds S] [--video-only] [--full-tiles] [--smoke] [--json]",
     "one operator, 1..N vehicles: handover p50/p95, operator CPU per vehicle, the servo loop "
     "against the bare loop; then each vehicle's video (kbit/s, rate estimate, SSIM) on the "
     "driven screen and the tiles, with a window"},
    {"soak",
     "[--duration S] [--kill-every MIN,MAX] [--seed N] [--port N] [--domain D] [--smoke] [--json]",
     "the study database under concurrency: a study with its console, two runs, the sqlite3 tool, "
     "random kill -9s; "
     "integrity after every kill, every acknowledged row found"},
    {"hands",
     "[--interfaces LIST] [--device FILE] [--steps N] [--nobody-s S] [--domain D] [--smoke] "
     "[--json]",
     "the mouse device as every interface's hands, through the real window under Xvfb: commands, "
     "input-to-command, pseudo-haptic ratios, contact to shake, servo p99, nobody engaged"},
    {"record", "[--track FILE] [--hours H] [--domain D] [--smoke] [--json]",
     "a grand prix lap with the view, without and with its session file: the recorder's CPU "
     "share, bytes per minute per channel, drops, servo p99; open and seek a one-hour file"},
};

using BenchMain = int (*)(int argc, const char* const* argv);
struct Bench {
  const char* name;
  BenchMain main;
};
constexpr Bench kBenches[] = {
    {"servo", BenchServoMain},         {"gravity", BenchGravityMain},
    {"skip", BenchSkipMain},           {"physics", BenchPhysicsMain},
    {"stability", BenchStabilityMain}, {"view", BenchViewMain},
    {"blimp", BenchBlimpMain},         {"link", BenchLinkMain},
    {"fuzz", BenchFuzzMain},           {"passivity", BenchPassivityMain},
    {"video", BenchVideoMain},         {"fleet", BenchFleetMain},
    {"soak", BenchSoakMain},           {"hands", BenchHandsMain},
    {"record", BenchRecordMain},
};

std::string UsageText(const std::string& only) {
  std::string text =
      "usage: haptel bench NAME [options]; each writes build/bench/NAME.csv, --json ends with one "
      "line;\n"
      "  --smoke: the same run shortened to seconds, for the tests (outputs in "
      "build/bench/smoke/,\n"
      "  \"smoke\":true in the JSON line: its figures are no measurements)\n";
  for (const Usage& u : kUsage) {
    if (!only.empty() && only != u.name) continue;
    text += "  haptel bench " + std::string(u.name) + " " + u.options + "\n      " + u.what + "\n";
  }
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace haptel;
  const std::string which = argc > 1 ? argv[1] : "";
  for (const Bench& bench : kBenches) {
    if (which != bench.name) continue;
    // Each benchmark parses argv from its own name on.
    return cli::Main({"haptel bench " + which, UsageText(which)}, argc - 1, argv + 1,
                     [&] { return bench.main(argc - 1, argv + 1); });
  }
  return cli::Main({"haptel bench", UsageText("")}, argc, argv, [&]() -> int {
    throw UsageError(which.empty() ? "missing benchmark name"
                                   : "unknown benchmark '" + which + "'");
  });
}
