#include "haptel/haptics/trace.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace haptel::haptics {

namespace {
constexpr char kMagic[8] = {'H', 'A', 'P', 'T', 'R', 'C', '0', '1'};
static_assert(sizeof(TraceRecord) == 16 + 8 * (kGloveJoints + kFingers),
              "trace records are packed");
}  // namespace

TraceRecord TraceRecord::FromWrist(Side side, const WristRaw& raw) {
  TraceRecord r;
  r.kind = kWrist;
  r.side = static_cast<uint8_t>(Index(side));
  r.t_ns = raw.t_ns;
  for (int i = 0; i < 3; ++i) r.values[i] = raw.position[i];
  for (int i = 0; i < 4; ++i) r.values[3 + i] = raw.orientation[i];
  return r;
}

TraceRecord TraceRecord::FromGlove(Side side, const GloveRaw& raw) {
  TraceRecord r;
  r.kind = kGlove;
  r.side = static_cast<uint8_t>(Index(side));
  r.t_ns = raw.t_ns;
  for (int j = 0; j < kGloveJoints; ++j) r.values[j] = raw.sensors[j];
  for (int f = 0; f < kFingers; ++f) r.values[kGloveJoints + f] = raw.grasp[f];
  return r;
}

TraceRecord TraceRecord::FromShake(Side side, const PseudoHapticReport& report) {
  TraceRecord r;
  r.kind = kShake;
  r.side = static_cast<uint8_t>(Index(side));
  r.t_ns = report.shake_start_ns;
  for (int i = 0; i < 3; ++i) {
    r.values[i] = report.target[i];
    r.values[3 + i] = report.hand[i];
    r.values[6 + i] = report.force[i];
    r.values[9 + i] = report.shake[i];
  }
  r.values[12] = report.held ? 1.0 : 0.0;
  r.values[13] = static_cast<double>(report.shakes);
  return r;
}

TraceRecord TraceRecord::Engaged(Side side, int64_t t_ns, bool engaged) {
  TraceRecord r;
  r.kind = kEngaged;
  r.side = static_cast<uint8_t>(Index(side));
  r.t_ns = t_ns;
  r.values[0] = engaged ? 1.0 : 0.0;
  return r;
}

WristRaw TraceRecord::ToWrist() const {
  WristRaw w;
  w.t_ns = t_ns;
  for (int i = 0; i < 3; ++i) w.position[i] = values[i];
  for (int i = 0; i < 4; ++i) w.orientation[i] = values[3 + i];
  return w;
}

GloveRaw TraceRecord::ToGlove() const {
  GloveRaw g;
  g.t_ns = t_ns;
  for (int j = 0; j < kGloveJoints; ++j) g.sensors[j] = values[j];
  for (int f = 0; f < kFingers; ++f) g.grasp[f] = values[kGloveJoints + f];
  return g;
}

PseudoHapticReport TraceRecord::ToShake() const {
  PseudoHapticReport p;
  for (int i = 0; i < 3; ++i) {
    p.target[i] = values[i];
    p.hand[i] = values[3 + i];
    p.force[i] = values[6 + i];
    p.shake[i] = values[9 + i];
  }
  p.held = values[12] != 0.0;
  p.shakes = static_cast<uint64_t>(values[13]);
  p.shake_start_ns = t_ns;
  return p;
}

TraceWriter::TraceWriter(const std::filesystem::path& file, size_t ring_capacity) : file_(file) {
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  out_ = std::fopen(file.c_str(), "wb");
  if (out_ == nullptr || std::fwrite(kMagic, 1, sizeof kMagic, out_) != sizeof kMagic) {
    if (out_ != nullptr) std::fclose(out_);
    throw std::runtime_error("trace: cannot write '" + file.string() +
                             "': " + std::strerror(errno));
  }
  for (auto& ring : rings_) ring = std::make_unique<SpscRing<TraceRecord>>(ring_capacity);
  thread_ = std::thread([this] { Drain(); });
}

TraceWriter::~TraceWriter() {
  stop_.store(true);
  thread_.join();
  std::fclose(out_);
}

bool TraceWriter::Push(const TraceRecord& record) {
  if (!recording_.load(std::memory_order_acquire)) return true;
  if (record.side >= kSides || !rings_[record.side]->Push(record)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

void TraceWriter::PushEngaged(int64_t t_ns, bool engaged) {
  if (!recording_.load(std::memory_order_acquire)) return;
  for (const Side side : {Side::kLeft, Side::kRight}) {
    if (!rings_[kSides]->Push(TraceRecord::Engaged(side, t_ns, engaged)))
      dropped_.fetch_add(1, std::memory_order_relaxed);
  }
}

void TraceWriter::Drain() {
  TraceRecord r;
  for (;;) {
    const bool stopping = stop_.load();
    bool any = false;
    for (auto& ring : rings_) {
      while (ring->Pop(r)) {
        std::fwrite(&r, sizeof r, 1, out_);
        written_.fetch_add(1, std::memory_order_relaxed);
        any = true;
      }
    }
    if (stopping && !any) break;
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::fflush(out_);
}

std::vector<TraceRecord> ReadTrace(const std::filesystem::path& file) {
  std::FILE* in = std::fopen(file.c_str(), "rb");
  if (in == nullptr) throw std::runtime_error("trace: cannot open '" + file.string() + "'");
  char magic[8] = {};
  if (std::fread(magic, 1, sizeof magic, in) != sizeof magic ||
      std::memcmp(magic, kMagic, sizeof magic) != 0) {
    std::fclose(in);
    throw std::runtime_error("trace: '" + file.string() + "' is not a Haptel trace (bad header)");
  }
  std::vector<TraceRecord> records;
  TraceRecord r;
  for (;;) {
    const size_t got = std::fread(&r, 1, sizeof r, in);
    if (got == 0) break;
    if (got != sizeof r ||
        (r.kind != TraceRecord::kWrist && r.kind != TraceRecord::kGlove &&
         r.kind != TraceRecord::kShake && r.kind != TraceRecord::kEngaged) ||
        r.side >= kSides) {
      std::fclose(in);
      throw std::runtime_error("trace: '" + file.string() + "': record " +
                               std::to_string(records.size()) +
                               (got != sizeof r ? " is truncated" : " is malformed"));
    }
    records.push_back(r);
  }
  std::fclose(in);
  // The sides and the session were written by their own rings: restore time order.
  std::stable_sort(records.begin(), records.end(),
                   [](const TraceRecord& a, const TraceRecord& b) { return a.t_ns < b.t_ns; });
  return records;
}

ReplayDevice::ReplayDevice(std::vector<TraceRecord> records, const DeviceDescription& description,
                           bool loop)
    : records_(std::move(records)), description_(description), loop_(loop) {
  if (records_.empty()) throw std::runtime_error("replay: the trace has no records");
  trace_start_ns_ = records_.front().t_ns;
  trace_span_ns_ = std::max<int64_t>(1, records_.back().t_ns - trace_start_ns_ + 1);
  for (auto& i : ignored_) i.store(0);
  has_engaged_ = std::any_of(records_.begin(), records_.end(),
                             [](const TraceRecord& r) { return r.kind == TraceRecord::kEngaged; });
}

bool ReplayDevice::finished(int64_t now_ns) const {
  const int64_t start = start_ns_.load();
  return !loop_ && !holding_.load() && start != 0 && now_ns - start >= trace_span_ns_;
}

long ReplayDevice::Due(Side side, TraceRecord::Kind kind, int64_t now_ns, size_t& cursor,
                       int64_t& round) {
  if (holding_.load(std::memory_order_acquire)) {
    // The first reading of this kind and side, without starting the clock.
    for (size_t i = 0; i < records_.size(); ++i) {
      if (records_[i].side == Index(side) && records_[i].kind == kind) return static_cast<long>(i);
    }
    return -1;
  }
  int64_t expected = 0;
  start_ns_.compare_exchange_strong(expected, now_ns);
  int64_t elapsed = now_ns - start_ns_.load();
  if (loop_) {
    if (elapsed / trace_span_ns_ != round) {
      round = elapsed / trace_span_ns_;
      cursor = 0;  // a new round from the top
    }
    elapsed %= trace_span_ns_;
  }
  const int64_t target = trace_start_ns_ + elapsed;
  long found = -1;
  size_t i = cursor;
  for (; i < records_.size() && records_[i].t_ns <= target; ++i) {
    if (records_[i].side == Index(side) && records_[i].kind == kind) found = static_cast<long>(i);
  }
  cursor = i;
  return found;
}

DeviceStatus ReplayDevice::ReadWrist(Side side, int64_t now_ns, WristRaw& out) {
  const long i =
      Due(side, TraceRecord::kWrist, now_ns, wrist_cursor_[Index(side)], wrist_round_[Index(side)]);
  if (i < 0) return DeviceStatus::kNoData;
  out = records_[static_cast<size_t>(i)].ToWrist();
  out.t_ns = now_ns;
  last_read_ns_[Index(side)] = now_ns;
  return DeviceStatus::kOk;
}

HandPresence ReplayDevice::Presence(Side side) {
  if (holding_.load(std::memory_order_acquire)) return HandPresence::kHeld;
  const int64_t start = start_ns_.load();
  const int64_t played = last_read_ns_[Index(side)] - start;
  if (has_engaged_) {
    const auto i = static_cast<size_t>(Index(side));
    if (start == 0) return HandPresence::kHeld;
    if (finished(last_read_ns_[i])) return HandPresence::kReleased;
    const long due =
        Due(side, TraceRecord::kEngaged, last_read_ns_[i], engaged_cursor_[i], engaged_round_[i]);
    if (due >= 0) engaged_[i] = records_[static_cast<size_t>(due)].values[0] != 0.0;
    return engaged_[i] ? HandPresence::kHeld : HandPresence::kReleased;
  }
  if (start == 0 || played < static_cast<int64_t>(kHeldAtStart_s * 1e9)) return HandPresence::kHeld;
  return HandPresence::kUnknown;
}

DeviceStatus ReplayDevice::ReadGlove(Side side, int64_t now_ns, GloveRaw& out) {
  const long i =
      Due(side, TraceRecord::kGlove, now_ns, glove_cursor_[Index(side)], glove_round_[Index(side)]);
  if (i < 0) return DeviceStatus::kNoData;
  out = records_[static_cast<size_t>(i)].ToGlove();
  out.t_ns = now_ns;
  return DeviceStatus::kOk;
}

DeviceStatus ReplayDevice::WriteWristForce(Side side, const Vec3d&) {
  ignored_[Index(side)].fetch_add(1, std::memory_order_relaxed);
  return DeviceStatus::kOk;
}

DeviceStatus ReplayDevice::WriteFingerForces(Side side, const std::array<double, kFingers>&) {
  ignored_[Index(side)].fetch_add(1, std::memory_order_relaxed);
  return DeviceStatus::kOk;
}

}  // namespace haptel::haptics
