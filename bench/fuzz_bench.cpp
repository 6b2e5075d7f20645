#include "fuzz_bench.hpp"

#include <arpa/inet.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/blimp_gesture.hpp"
#include "haptel/config/calibration.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gamepad.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/keyboard.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/study.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/servo/servo_output.hpp"
#include "haptel/servo/sim_servo_controller.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/questionnaire.hpp"
#include "haptel/testing/loopback.hpp"
#include "haptel/udp/udp_protocol.hpp"
#include "haptel/vehicles/candump_log.hpp"
#include "haptel/vehicles/odrive_can.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace fs = std::filesystem;
namespace udp = haptics::udp;
using Bytes = std::vector<uint8_t>;

namespace {

// --- What a crash or a hang leaves behind: the input, written where the
// signal handler can (no allocation, only write(2)). ---
constexpr size_t kMaxInput = 1 << 20;
uint8_t g_input[kMaxInput];
std::atomic<size_t> g_input_size{0};
char g_crash_file[512] = "";
std::atomic<int64_t> g_started_ns{0};
constexpr double kHang_s = 5.0;

void WriteInput(const char* file) {
  const int fd = ::open(file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;
  const ssize_t ignored = ::write(fd, g_input, g_input_size.load());
  (void)ignored;
  ::close(fd);
}

void OnCrash(int sig) {
  WriteInput(g_crash_file);
  const char message[] =
      "haptel bench fuzz: CRASH: the input is in the file named fuzz-<target>-crash.bin\n";
  const ssize_t ignored = ::write(2, message, sizeof message - 1);
  (void)ignored;
  signal(sig, SIG_DFL);
  raise(sig);
}

/// Stops the process when one input takes longer than kHang_s.
class HangWatch {
 public:
  explicit HangWatch(std::string file) : file_(std::move(file)) {
    thread_ = std::thread([this] {
      while (!stop_.load()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        const int64_t started = g_started_ns.load();
        if (started != 0 && NsToS(MonotonicNs() - started) > kHang_s) {
          WriteInput(file_.c_str());
          std::fprintf(stderr,
                       "haptel bench fuzz: HANG: one input took more than %.0f s; it is in %s\n",
                       kHang_s, file_.c_str());
          std::_Exit(1);
        }
      }
    });
  }
  ~HangWatch() {
    stop_.store(true);
    thread_.join();
  }

 private:
  std::string file_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

Bytes ReadBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& file, const Bytes& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

/// Seeded mutations of seed inputs.
class Mutator {
 public:
  Mutator(uint64_t seed, bool text) : random_(seed), text_(text) {}

  Bytes Mutate(const std::vector<Bytes>& seeds, size_t which) {
    Bytes b = seeds[which];
    const int rounds = 1 + static_cast<int>(Below(4));
    for (int r = 0; r < rounds; ++r) Once(b, seeds);
    if (b.size() > kMaxInput) b.resize(kMaxInput);
    return b;
  }
  uint64_t Below(uint64_t n) { return n == 0 ? 0 : random_() % n; }
  std::mt19937_64& random() { return random_; }

 private:
  void Once(Bytes& b, const std::vector<Bytes>& seeds) {
    static const char* const kText[] = {
        "nan",         "-nan",  "inf",       "-1e308",   "1e400", "-0", "0x7fffffff",
        "-2147483649", "[",     "]",         "{",        "}",     ":",  ": ",
        "- ",          "\n",    "  ",        "\t",       "&a ",   "*a", "!!binary ",
        "''",          "\"",    "~",         "null",     "<",     ">",  "</",
        "/>",          "&amp;", "<![CDATA[", "\xff\xfe", "#",     ",",  "999999999999999999999",
        "1.5",         "true",  "yes",       "?"};
    static const uint8_t kBinary[] = {0x00, 0xff, 0x7f, 0x80, 0x01, 0xfe};
    const uint64_t op = Below(b.empty() ? 3 : 8);
    switch (op) {
      case 0: {  // insert an interesting token or byte
        const size_t at = Below(b.size() + 1);
        if (text_) {
          const char* t = kText[Below(std::size(kText))];
          b.insert(b.begin() + static_cast<long>(at), t, t + std::strlen(t));
        } else {
          b.insert(b.begin() + static_cast<long>(at), kBinary[Below(std::size(kBinary))]);
        }
        break;
      }
      case 1: {  // splice: this one's head, another seed's tail
        const Bytes& other = seeds[Below(seeds.size())];
        const size_t keep = Below(b.size() + 1);
        const size_t from = Below(other.size() + 1);
        b.resize(keep);
        b.insert(b.end(), other.begin() + static_cast<long>(from), other.end());
        break;
      }
      case 2: {  // a few random bytes
        const size_t at = Below(b.size() + 1);
        const size_t n = 1 + Below(8);
        for (size_t i = 0; i < n; ++i)
          b.insert(b.begin() + static_cast<long>(at), static_cast<uint8_t>(random_()));
        break;
      }
      case 3:  // flip a bit
        b[Below(b.size())] ^= static_cast<uint8_t>(1u << Below(8));
        break;
      case 4:  // set a byte
        b[Below(b.size())] = static_cast<uint8_t>(random_());
        break;
      case 5: {  // delete a chunk
        const size_t at = Below(b.size());
        const size_t n = std::min(b.size() - at, 1 + Below(32));
        b.erase(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + n));
        break;
      }
      case 6: {  // duplicate a chunk somewhere
        const size_t at = Below(b.size());
        const size_t n = std::min(b.size() - at, 1 + Below(64));
        const Bytes chunk(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + n));
        const size_t to = Below(b.size() + 1);
        b.insert(b.begin() + static_cast<long>(to), chunk.begin(), chunk.end());
        break;
      }
      default:  // truncate
        b.resize(Below(b.size() + 1));
        break;
    }
  }

  std::mt19937_64 random_;
  bool text_;
};

/// One target: its seeds, and how one input is parsed (true: a value).
struct Target {
  std::vector<Bytes> seeds;
  bool text = true;
  std::function<bool(size_t seed, const Bytes& input)> parse;
  /// Measured once the inputs are done (the console: its page under slow clients).
  std::function<double()> after;
};

/// A byte stream in memory: reads what it is given, takes what is written.
class MemoryStream final : public servo::ByteStream {
 public:
  explicit MemoryStream(Bytes in, Bytes* written = nullptr)
      : in_(std::move(in)), written_(written) {}
  size_t Write(const uint8_t* data, size_t size) override {
    if (written_ != nullptr) written_->insert(written_->end(), data, data + size);
    return size;
  }
  size_t Read(uint8_t* data, size_t size) override {
    const size_t n = std::min(size, in_.size() - at_);
    std::memcpy(data, in_.data() + at_, n);
    at_ += n;
    return n;
  }
  std::string name() const override { return "memory"; }

 private:
  Bytes in_;
  size_t at_ = 0;
  Bytes* written_;
};

// ------------------------------------------------------------------ targets

/// A copy of the shipped config folder to fuzz in (relative references keep working).
fs::path FuzzCopy() {
  const fs::path dir = fs::temp_directory_path() / ("haptel-fuzz-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy(ShippedFile("config"), dir / "config", fs::copy_options::recursive);
  return dir / "config";
}

using Loader = std::function<void(const fs::path&)>;

/// A target whose inputs are files: each seed is written over its file in
/// the copy, read by its loader, and put back.
Target FileTarget(std::vector<std::pair<fs::path, Loader>> loaded) {
  Target t;
  for (const auto& [file, load] : loaded) t.seeds.push_back(ReadBytes(file));
  auto files = std::make_shared<std::vector<std::pair<fs::path, Loader>>>(std::move(loaded));
  auto originals = std::make_shared<std::vector<Bytes>>(t.seeds);
  t.parse = [files, originals](size_t seed, const Bytes& input) {
    const auto& [file, load] = (*files)[seed];
    WriteBytes(file, input);
    bool ok = true;
    try {
      load(file);
    } catch (const std::exception&) {
      ok = false;
    }
    WriteBytes(file, (*originals)[seed]);
    return ok;
  };
  return t;
}

Target ConfigTarget(const fs::path& copy) {
  const std::vector<Loader> loaders = {
      [](const fs::path& f) { LoadRun(f); },         [](const fs::path& f) { LoadTrack(f); },
      [](const fs::path& f) { LoadBlimpCourse(f); }, [](const fs::path& f) { LoadVehicle(f); },
      [](const fs::path& f) { LoadDevice(f); },      [](const fs::path& f) { LoadPhysics(f); },
      [](const fs::path& f) { LoadStudy(f); },       [](const fs::path& f) { LoadCockpit(f); },
      [](const fs::path& f) { LoadGesture(f); },     [](const fs::path& f) { LoadKeyboard(f); },
      [](const fs::path& f) { LoadGamepad(f); },     [](const fs::path& f) { LoadBlimpGesture(f); },
      [](const fs::path& f) { LoadCalibration(f); },
  };
  // Each file's loader is the first that takes it unmutated.
  std::vector<std::pair<fs::path, Loader>> loaded;
  for (const auto& entry : fs::recursive_directory_iterator(copy)) {
    if (entry.path().extension() != ".yaml" || entry.path().parent_path().filename() == "scenes")
      continue;
    for (const Loader& load : loaders) {
      try {
        load(entry.path());
      } catch (const std::exception&) {
        continue;
      }
      loaded.emplace_back(entry.path(), load);
      break;
    }
  }
  return FileTarget(std::move(loaded));
}

Target SceneTarget(const fs::path& copy) {
  const Loader load = [](const fs::path& f) { LoadSceneFile(f); };
  return FileTarget({{copy / "scenes/table.yaml", load}, {copy / "scenes/table.xml", load}});
}

Target UdpTarget() {
  Target t;
  t.text = false;
  std::vector<udp::Message> messages(5);
  messages[0].payload = udp::GloveRequest{};
  messages[1].payload = udp::WristForce{};
  messages[2].payload = udp::FingerForce{};
  messages[3].payload = udp::ErrorReply{};
  udp::GloveReply glove;
  glove.device_ns = 123456789;
  messages[4].payload = glove;
  for (size_t i = 0; i < messages.size(); ++i) {
    messages[i].sequence = static_cast<uint32_t>(i + 1);
    udp::Buffer buffer{};
    const size_t n = udp::Encode(messages[i], buffer);
    if (n > 0) t.seeds.emplace_back(buffer.begin(), buffer.begin() + static_cast<long>(n));
  }
  t.parse = [](size_t, const Bytes& input) {
    udp::Message out;
    return udp::Decode(input, out) == udp::DecodeStatus::kOk;
  };
  return t;
}

Target ServoTarget() {
  Target t;
  t.text = false;
  auto configs = std::make_shared<std::vector<ServoControllerConfig>>();
  for (const char* file :
       {"config/vehicles/sim-blimp-maestro.yaml", "config/vehicles/sim-blimp-sc8000.yaml"}) {
    ServoControllerConfig c = LoadVehicle(ShippedFile(file)).servo;
    configs->push_back(c);
    // The adapter's own frames: valid commands of each protocol.
    Bytes written;
    servo::ServoOutput out(c, std::make_unique<MemoryStream>(Bytes{}, &written));
    for (double p : {1000.0, 1500.0, 2000.0}) {
      std::array<double, kBlimpChannels> pulses;
      pulses.fill(p);
      out.Send(pulses);
      out.Update(0.5);
    }
    t.seeds.push_back(written);
  }
  // Replies a Maestro sends (Get Errors: two bytes), as seeds for the adapter's reader.
  t.seeds.push_back({0x00, 0x00, 0x10, 0x00});
  t.parse = [configs](size_t seed, const Bytes& input) {
    if (seed < 2) {
      // The device's decoder (the simulated controller), both protocols.
      servo::SimServoController device((*configs)[seed], std::make_unique<MemoryStream>(input));
      device.Update(0.01);
      return device.counters().commands > 0;
    }
    // The real adapter reading whatever the controller sends back.
    servo::ServoOutput out((*configs)[0], std::make_unique<MemoryStream>(input));
    std::array<double, kBlimpChannels> pulses;
    pulses.fill(1500.0);
    out.Send(pulses);
    out.Update(0.0);
    out.Update(1.0);
    return out.counters().error_replies > 0;
  };
  return t;
}

Target CanTarget() {
  Target t;
  t.text = true;
  // Candump lines; the raw frames come from the same bytes.
  for (const char* line : {"02D#0000C03F00000000", "021#0100000008000000", "03E#0300", "001#0100",
                           "7FF#", "12345678#DEADBEEF"}) {
    t.seeds.emplace_back(line, line + std::strlen(line));
  }
  t.parse = [](size_t, const Bytes& input) {
    bool any = false;
    can_frame parsed{};
    any |= vehicles::ParseCandumpFrame(std::string(input.begin(), input.end()), parsed);
    can_frame f{};
    if (!input.empty()) {
      f.can_id = (input[0] | (input.size() > 1 ? input[1] << 8 : 0)) & 0x7ff;
      f.can_dlc =
          static_cast<uint8_t>(input.size() > 2 ? input[2] % 16 : 0);  // past 8 is malformed
      for (size_t i = 0; i < 8 && 3 + i < input.size(); ++i) f.data[i] = input[3 + i];
    }
    namespace od = vehicles::odrive;
    any |= od::DecodeHeartbeat(f).has_value();
    any |= od::DecodeEncoderEstimates(f).has_value();
    any |= od::DecodeSetInputVel(f).has_value();
    any |= od::DecodeControllerMode(f).has_value();
    any |= od::DecodeAxisState(f).has_value();
    any |= vehicles::io_node::DecodeInputs(f).has_value();
    any |= vehicles::io_node::DecodeHeartbeat(f).has_value();
    return any;
  };
  return t;
}

template <typename PubSub, typename Msg>
Bytes Serialized(Msg m) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
  type.serialize(&m, &payload);
  return Bytes(payload.data, payload.data + payload.length);
}

template <typename PubSub, typename Msg>
bool Deserialize(const Bytes& input, Msg& out) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      static_cast<uint32_t>(std::max<size_t>(input.size(), 1)));
  std::memcpy(payload.data, input.data(), input.size());
  payload.length = static_cast<uint32_t>(input.size());
  try {
    return type.deserialize(&payload, &out);
  } catch (const std::exception&) {
    return false;  // Fast CDR throws NotEnoughMemoryException on a short buffer
  }
}

Target DdsTarget() {
  Target t;
  t.text = false;
  msg::TreadCommand drive;
  drive.seq(7);
  drive.left(0.5f);
  drive.right(-0.25f);
  drive.session(42);
  drive.operator_name("haptel run, ana@lab pid 1");
  t.seeds.push_back(Serialized<msg::TreadCommandPubSubType>(drive));
  msg::BlimpCommand blimp;
  blimp.power(0.5f);
  blimp.camera_pan(0.3f);
  blimp.operator_name("haptel run, bo@lab pid 2");
  t.seeds.push_back(Serialized<msg::BlimpCommandPubSubType>(blimp));
  msg::VehicleState state;
  state.fault_message("a motor controller's error");
  state.owner("haptel run, ana@lab pid 1");
  t.seeds.push_back(Serialized<msg::VehicleStatePubSubType>(state));
  msg::BlimpState bstate;
  bstate.owner("x");
  t.seeds.push_back(Serialized<msg::BlimpStatePubSubType>(bstate));
  t.parse = [](size_t seed, const Bytes& input) {
    switch (seed) {
      case 0: {
        msg::TreadCommand c;
        if (!Deserialize<msg::TreadCommandPubSubType>(input, c)) return false;
        // The vehicle node's check of the robot family's command.
        TreadCommand command;
        return link::RobotMessages::Decode(c, command);
      }
      case 1: {
        msg::BlimpCommand c;
        if (!Deserialize<msg::BlimpCommandPubSubType>(input, c)) return false;
        link::BlimpMessages::Command command;
        return link::BlimpMessages::Decode(c, command);
      }
      case 2: {
        msg::VehicleState s;
        return Deserialize<msg::VehicleStatePubSubType>(input, s) && std::isfinite(s.x());
      }
      default: {
        msg::BlimpState s;
        return Deserialize<msg::BlimpStatePubSubType>(input, s) && std::isfinite(s.z());
      }
    }
  };
  return t;
}

}  // namespace

/// One HTTP exchange with the console: `request` sent as is, the sending
/// side shut (a request cut short ends at once, not at the console's
/// deadline); the answer's status, or 0 when it closed without one.
int HttpExchange(int port, const Bytes& request) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error("bench fuzz console: no socket");
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  if (connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
    close(fd);
    throw std::runtime_error("bench fuzz console: the console stopped accepting connections");
  }
  size_t sent = 0;
  while (sent < request.size()) {
    const ssize_t n = send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) break;  // the console has refused and closed: its answer is still read
    sent += static_cast<size_t>(n);
  }
  shutdown(fd, SHUT_WR);
  std::string answer;
  char buffer[4096];
  for (ssize_t n; (n = recv(fd, buffer, sizeof buffer, 0)) > 0;) {
    if (answer.size() < 64) answer.append(buffer, static_cast<size_t>(n));
  }
  close(fd);
  int status = 0;
  return std::sscanf(answer.c_str(), "HTTP/1.%*d %d", &status) == 1 ? status : 0;
}

/// The slowest of 5 page requests (GET /, from 127.0.0.1, the
/// experimenter's address) while 100 slow connections hold on: 40 from
/// 127.0.0.1 and 3 from each of 127.0.0.2..21, half dribbling a partial
/// request a byte every 50 ms, half silent, each opened again when the
/// console closes it. A request not answered 200 within 10 s counts 10 s.
double PageUnderSlowClientsMs(int port) {
  const std::string partial =
      "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nX-Slow: ";
  std::vector<int> fds(100, -1);
  std::vector<size_t> sent(100, 0);
  auto from = [](size_t i) {
    return i < 40 ? std::string("127.0.0.1") : "127.0.0." + std::to_string(2 + (i - 40) / 3);
  };
  std::atomic<bool> stop{false};
  std::atomic<int> opened{0};
  std::thread slow([&] {
    while (!stop.load()) {
      for (size_t i = 0; i < fds.size(); ++i) {
        if (fds[i] < 0) {
          fds[i] = testing::ConnectFrom(from(i), port, 10);
          sent[i] = 0;
          if (fds[i] >= 0) ++opened;
          continue;
        }
        pollfd p{fds[i], POLLIN, 0};
        if (poll(&p, 1, 0) > 0) {
          close(fds[i]);
          fds[i] = -1;
        } else if (i % 2 == 0) {
          const char byte = sent[i] < partial.size() ? partial[sent[i]] : 'x';
          if (send(fds[i], &byte, 1, MSG_NOSIGNAL | MSG_DONTWAIT) == 1) ++sent[i];
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    for (const int fd : fds) {
      if (fd >= 0) close(fd);
    }
  });
  for (int i = 0; i < 600 && opened.load() < 100; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  double slowest_ms = 0.0;
  for (int i = 0; i < 5; ++i) {
    const int64_t t0 = MonotonicNs();
    const int fd = testing::ConnectFrom("127.0.0.1", port, 10);
    std::string answer;
    if (fd >= 0) {
      const std::string r = "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                            "\r\nConnection: close\r\n\r\n";
      (void)!send(fd, r.data(), r.size(), MSG_NOSIGNAL);
      char buffer[4096];
      for (ssize_t n; (n = recv(fd, buffer, sizeof buffer, 0)) > 0;)
        answer.append(buffer, static_cast<size_t>(n));
      close(fd);
    }
    const bool ok = answer.rfind("HTTP/1.1 200", 0) == 0;
    slowest_ms = std::max(slowest_ms, ok ? NsToS(MonotonicNs() - t0) * 1e3 : 10000.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  stop.store(true);
  slow.join();
  return slowest_ms;
}

/// The experimenter's console, served for real on a free loopback port over a
/// study of its own (one trial driven, the thesis questionnaire), fed
/// mutated requests: every route, forms with their token, a chunked body.
/// Accepted: answered 2xx or 3xx; rejected: a 4xx/5xx or closed unanswered.
Target ConsoleTarget(const fs::path& dir) {
  Target t;
  StudyConfig config;
  config.file = dir / "fuzz.yaml";
  std::ofstream(config.file) << "name: fuzz\n";
  config.name = "fuzz";
  config.operators = "person";
  config.conditions = {{"cockpit", "cockpit"}, {"gesture", "gesture"}};
  config.participants = {{"A", ""}};
  config.questionnaires = {"thesis"};
  const std::vector<study::PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  const std::map<std::string, study::Questionnaire> questionnaires = {
      {"thesis", study::FindQuestionnaire(ShippedFile("config/questionnaires"), "thesis")}};
  study::ConsoleOptions options;
  options.port = 0;
  options.thumbnail = true;
  auto console =
      std::make_shared<study::StudyConsole>(config, plan, dir / "fuzz.db", questionnaires, options);
  console->SetPicture({0xFF, 0xD8, 0xFF, 0xD9}, 1);
  console->SetLive("fuzzing");
  const int port = console->port();
  // The form token, as a browser has it from a page.
  std::string token;
  {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    std::string page;
    if (connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) == 0) {
      const std::string r =
          "GET /login HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n";
      (void)!send(fd, r.data(), r.size(), MSG_NOSIGNAL);
      char buffer[4096];
      for (ssize_t n; (n = recv(fd, buffer, sizeof buffer, 0)) > 0;)
        page.append(buffer, static_cast<size_t>(n));
    }
    close(fd);
    const size_t at = page.find("name=\"csrf\" value=\"");
    if (at != std::string::npos) token = page.substr(at + 19, 32);
  }
  if (token.size() != 32)
    throw std::runtime_error("bench fuzz console: the console's page has no form token");
  const std::string host = "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";
  auto post = [&](const std::string& path, const std::string& body, const std::string& extra = "") {
    return "POST " + path + " HTTP/1.1\r\n" + host + extra +
           "Content-Type: application/x-www-form-urlencoded\r\nContent-Length: " +
           std::to_string(body.size()) + "\r\n\r\n" + body;
  };
  static const std::string kChunkedHead =
      "Content-Type: application/x-www-form-urlencoded\r\nTransfer-Encoding: chunked\r\n\r\n";
  auto chunked = [&](const std::string& path, const std::vector<std::string>& chunks) {
    std::string r = "POST " + path + " HTTP/1.1\r\n" + host + kChunkedHead;
    char size[32];
    for (const std::string& c : chunks) {
      std::snprintf(size, sizeof size, "%zx\r\n", c.size());
      r += size + c + "\r\n";
    }
    return r + "0\r\n\r\n";
  };
  const std::vector<std::string> requests = {
      "GET / HTTP/1.1\r\n" + host + "\r\n",
      "GET /questionnaire?participant=A&condition=gesture&name=thesis HTTP/1.1\r\n" + host +
          "Accept: text/html\r\nCookie: haptel_console=x; other=1\r\n\r\n",
      "GET /status.json HTTP/1.1\r\n" + host + "\r\n",
      "GET /video.jpg?n=1 HTTP/1.1\r\n" + host + "Range: bytes=0-1\r\n\r\n",
      post("/answers",
           "participant=A&condition=gesture&questionnaire=thesis&easy_to_learn=4&efficient=5&"
           "remarks=" +
               std::string("%E6%BC%A2%20ok&csrf=") + token),
      post("/redo", "participant=A&position=1&csrf=" + token,
           "Origin: http://127.0.0.1:" + std::to_string(port) +
               "\r\nSec-Fetch-Site: same-origin\r\n"),
      post("/participants", "id=P2&csrf=" + token),
      post("/abort", "csrf=" + token),
      post("/login", "token=abc&csrf=" + token),
      "POST /answers HTTP/1.1\r\n" + host +
          "Content-Type: application/x-www-form-urlencoded\r\nTransfer-Encoding: chunked\r\n\r\n"
          "10\r\nparticipant=A&co\r\n0\r\n\r\n",
      // Chunked bodies: a whole note; past the limit; to a route that takes
      // only a length (411); chunk sizes that are not sizes, or lie.
      chunked("/notes", {"participant=A&position=1&", "text=chunked%20note&csrf=" + token}),
      chunked("/answers", std::vector<std::string>(40, std::string(4000, 'x'))),
      chunked("/participants", {"id=P3&csrf=" + token}),
      "POST /notes HTTP/1.1\r\n" + host + kChunkedHead + "zz\r\nparticipant=A\r\n0\r\n\r\n",
      "POST /notes HTTP/1.1\r\n" + host + kChunkedHead +
          "ffffffffffffffffffff\r\nparticipant=A\r\n0\r\n\r\n",
      "POST /notes HTTP/1.1\r\n" + host + kChunkedHead + "-1\r\nx\r\n0\r\n\r\n",
      "POST /answers HTTP/1.1\r\n" + host + kChunkedHead + "100\r\nparticipant=A\r\n0\r\n\r\n",
      "POST /answers HTTP/1.1\r\n" + host + kChunkedHead +
          "5;ext=1\r\nabcde\r\n0\r\nTrailer: x\r\n\r\n",
      "POST /notes HTTP/1.1\r\n" + host + kChunkedHead + std::string(20000, '1'),
  };
  for (const std::string& r : requests) t.seeds.emplace_back(r.begin(), r.end());
  t.parse = [console, port](size_t, const Bytes& input) {
    const int status = HttpExchange(port, input);
    return status >= 200 && status < 400;
  };
  t.after = [console, port] { return PageUnderSlowClientsMs(port); };
  return t;
}

std::vector<std::string> FuzzTargets() {
  return {"config", "scene", "udp", "servo", "can", "dds", "console"};
}

FuzzResult Fuzz(const std::string& name, uint64_t inputs, uint64_t seed) {
  std::optional<fs::path> copy;
  Target target;
  if (name == "config" || name == "scene") {
    copy = FuzzCopy();
    target = name == "config" ? ConfigTarget(*copy) : SceneTarget(*copy);
  } else if (name == "udp") {
    target = UdpTarget();
  } else if (name == "servo") {
    target = ServoTarget();
  } else if (name == "can") {
    target = CanTarget();
  } else if (name == "dds") {
    target = DdsTarget();
  } else if (name == "console") {
    copy = fs::temp_directory_path() / ("haptel-fuzz-" + std::to_string(getpid())) / "console";
    fs::remove_all(copy->parent_path());
    fs::create_directories(*copy);
    target = ConsoleTarget(*copy);
  } else {
    throw std::invalid_argument("unknown fuzz target '" + name + "'");
  }
  if (target.seeds.empty()) throw std::runtime_error("fuzz target '" + name + "' has no seeds");
  const fs::path dir = BenchDir();
  fs::create_directories(dir);
  std::snprintf(g_crash_file, sizeof g_crash_file, "%s/fuzz-%s-crash.bin", dir.c_str(),
                name.c_str());
  for (int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL}) signal(sig, OnCrash);
  HangWatch watch((dir / ("fuzz-" + name + "-hang.bin")).string());

  FuzzResult r;
  r.target = name;
  Mutator mutator(seed, target.text);
  const int64_t start = MonotonicNs();
  for (uint64_t i = 0; i < inputs; ++i) {
    const size_t which = static_cast<size_t>(mutator.Below(target.seeds.size()));
    // One in 64 inputs is the seed itself, so the valid path stays covered.
    const Bytes input = i % 64 == 0 ? target.seeds[which] : mutator.Mutate(target.seeds, which);
    std::memcpy(g_input, input.data(), input.size());
    g_input_size.store(input.size());
    const int64_t t0 = MonotonicNs();
    g_started_ns.store(t0);
    const bool accepted = target.parse(which, input);
    const int64_t t1 = MonotonicNs();
    g_started_ns.store(0);
    r.slowest_ms = std::max(r.slowest_ms, NsToS(t1 - t0) * 1e3);
    ++r.inputs;
    (accepted ? r.accepted : r.rejected)++;
  }
  r.seconds = NsToS(MonotonicNs() - start);
  if (target.after) r.page_under_slow_clients_ms = target.after();
  for (int sig : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL}) signal(sig, SIG_DFL);
  target = {};  // the console, if it is one, stops before its folder goes
  if (copy) fs::remove_all(copy->parent_path());
  return r;
}

int BenchFuzzMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  uint64_t inputs = 1000000;
  uint64_t seed = 1;
  std::vector<std::string> targets = FuzzTargets();
  try {
    const Args args(argc, argv, {"inputs", "target", "seed"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    if (smoke) inputs = 300;  // every target; the config and scene loaders take about 1 ms an input
    if (auto n = args.Number("inputs", 1.0, 1e9)) inputs = static_cast<uint64_t>(*n);
    if (auto s = args.Number("seed", 0.0, 1e18)) seed = static_cast<uint64_t>(*s);
    if (auto t = args.Value("target")) {
      const auto all = FuzzTargets();
      if (std::find(all.begin(), all.end(), *t) == all.end()) {
        throw UsageError(
            "option --target: expected one of config, scene, udp, servo, can, dds, console");
      }
      targets = {*t};
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench fuzz: %s\n", e.what());
    return 2;
  }
  PrintSmokeNote("fuzz", smoke, "%llu inputs per target", static_cast<unsigned long long>(inputs));
  const auto dir = OutputDir(smoke);
  std::printf("haptel bench fuzz: %llu inputs per target, seed %llu\n\n",
              static_cast<unsigned long long>(inputs), static_cast<unsigned long long>(seed));
  std::printf("  target   inputs      accepted   rejected   time s   inputs/s   slowest ms\n");
  std::vector<FuzzResult> results;
  for (const std::string& t : targets) {
    const FuzzResult r = Fuzz(t, inputs, seed);
    results.push_back(r);
    std::printf("  %-7s  %-10llu  %-9llu  %-9llu  %7.1f  %9.0f  %10.2f\n", t.c_str(),
                static_cast<unsigned long long>(r.inputs),
                static_cast<unsigned long long>(r.accepted),
                static_cast<unsigned long long>(r.rejected), r.seconds,
                r.inputs / std::max(r.seconds, 1e-9), r.slowest_ms);
    if (r.page_under_slow_clients_ms >= 0.0) {
      std::printf(
          "           its page under 100 slow connections (40 from the same address): slowest of 5 "
          "answered in %.1f ms\n",
          r.page_under_slow_clients_ms);
    }
    std::fflush(stdout);
  }
  {
    std::ofstream csv(dir / "fuzz.csv");
    csv << "target,inputs,accepted,rejected,seconds,slowest_ms\n";
    for (const auto& r : results) {
      csv << r.target << "," << r.inputs << "," << r.accepted << "," << r.rejected << ","
          << r.seconds << "," << r.slowest_ms << "\n";
    }
  }
  std::printf("\n  no crash, no hang; wrote %s/fuzz.csv\n", dir.c_str());
  if (json) {
    std::ostringstream o;
    o << "{\"crashes\":0,\"hangs\":0,\"targets\":[";
    for (size_t i = 0; i < results.size(); ++i) {
      const auto& r = results[i];
      o << (i ? "," : "") << "{\"target\":" << JsonString(r.target) << ",\"inputs\":" << r.inputs
        << ",\"accepted\":" << r.accepted << ",\"rejected\":" << r.rejected
        << ",\"seconds\":" << JsonNumber(r.seconds)
        << ",\"slowest_ms\":" << JsonNumber(r.slowest_ms);
      if (r.page_under_slow_clients_ms >= 0.0) {
        o << ",\"page_under_slow_clients_ms\":" << JsonNumber(r.page_under_slow_clients_ms);
      }
      o << "}";
    }
    o << "]}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return 0;
}

}  // namespace haptel::bench
