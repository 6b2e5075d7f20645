// The link-rate estimator on synthetic arrival traces: a sender that follows
// the estimator's target through a bottleneck of the test's own (a
// drop-tail queue served at the link's capacity, a propagation delay, a
// little jitter), in simulated time.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <deque>
#include <functional>
#include <random>
#include <stdexcept>
#include <vector>

#include "haptel/video/rate_estimator.hpp"

using haptel::video::LinkUsage;
using haptel::video::RateEstimator;
using haptel::video::RateEstimatorConfig;

namespace {

/// What the run saw, per frame sent.
struct Sample {
  double t_s;
  double target_kbps;
  double capacity_kbps;
};

/// A video sender at `fps` following the estimator's target (applied when
/// FeedbackDue says it is sent, `feedback_delay_s` later) through a link of
/// `capacity(t)` kbit/s, a drop-tail queue `queue_s` deep, `delay_s` of
/// propagation, uniform jitter of ±`jitter_s` and random loss `loss`.
struct LinkRun {
  std::function<double(double)> capacity;
  double fps = 30.0;
  double delay_s = 0.02;
  double jitter_s = 0.0;
  double loss = 0.0;
  double queue_s = 0.1;
  double feedback_delay_s = 0.02;
  uint32_t seed = 1;

  std::vector<Sample> Run(RateEstimator& estimator, double duration_s) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Sample> out;
    double sender_kbps = RateEstimatorConfig{}.start_kbps;
    std::deque<std::pair<double, double>> on_their_way;  // (when it reaches the sender, kbps)
    double link_free_s = 0;  // when the bottleneck has sent all it holds
    uint64_t frame = 0;
    for (double t = 0; t < duration_s; t += 1.0 / fps, ++frame) {
      while (!on_their_way.empty() && t >= on_their_way.front().first) {
        sender_kbps = on_their_way.front().second;
        on_their_way.pop_front();
      }
      // Frames vary in size around the rate (±20 %), as an encoder's do.
      const double bytes = sender_kbps * 1000.0 / 8.0 / fps * (0.8 + 0.4 * unit(rng));
      const double c = capacity(t) * 1000.0;  // bit/s
      const double start = std::max(t, link_free_s);
      out.push_back({t, estimator.target_kbps(), capacity(t)});
      if (start - t > queue_s) continue;  // the queue is full: dropped
      link_free_s = start + bytes * 8.0 / c;
      if (unit(rng) < loss) continue;
      const double arrival = link_free_s + delay_s + jitter_s * (2 * unit(rng) - 1);
      estimator.OnFrame(frame, t, arrival, static_cast<size_t>(bytes));
      if (estimator.FeedbackDue(arrival))
        on_their_way.emplace_back(arrival + feedback_delay_s, estimator.target_kbps());
    }
    return out;
  }
};

/// A JPEG camera behind the link, as the vehicle's encoder ladder makes it:
/// coarse rungs (quality at full resolution, then half resolution, then
/// frames skipped), the highest whose rate fits the target taken one rung a
/// step every few frames; each frame leaves as one burst at its capture time
/// (one datagram of up to 64 kB on a loopback, or packets of `packet_bytes`),
/// through a drop-tail queue served at the capacity. A frame arrives when its
/// last packet does, and is lost when any of its packets is (a best-effort
/// sample cut short).
struct BurstyJpegRun {
  double capacity_kbps = 1000.0;
  double fps = 30.0;
  double delay_s = 0.02;
  double queue_s = 0.1;
  size_t packet_bytes = 64000;
  double feedback_delay_s = 0.02;
  uint32_t seed = 3;

  /// The ladder's rungs (kbit/s at `fps`, and the share of frames sent),
  /// from the shipped camera's measured JPEG sizes (haptel bench video:
  /// quality 80 at 640x480 is about 25 kB a frame; quality 20 at half
  /// resolution about 2 kB).
  struct Rung {
    double kbps;
    int every;  ///< one frame in `every` is sent
  };
  static constexpr std::array<Rung, 11> kRungs{{{6000, 1},
                                                {5000, 1},
                                                {4200, 1},
                                                {3500, 1},
                                                {3000, 1},
                                                {2400, 1},
                                                {1800, 1},
                                                {510, 1},
                                                {510, 2},
                                                {510, 3},
                                                {510, 4}}};

  std::vector<Sample> Run(RateEstimator& estimator, double duration_s) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Sample> out;
    double followed_kbps = 1e9;  // the vehicle starts at its file's setting: the top rung
    std::deque<std::pair<double, double>> on_their_way;
    size_t rung = 0;
    int frames_at_rung = 0;
    double link_free_s = 0;
    uint64_t seq = 0;
    int64_t tick = 0;
    for (double t = 0; t < duration_s; t = static_cast<double>(++tick) / fps) {
      while (!on_their_way.empty() && t >= on_their_way.front().first) {
        followed_kbps = on_their_way.front().second;
        on_their_way.pop_front();
      }
      out.push_back({t, estimator.target_kbps(), capacity_kbps});
      // The receiver's silence check, as often as frames would come.
      if (estimator.OnSilence(t + delay_s) && estimator.FeedbackDue(t + delay_s)) {
        on_their_way.emplace_back(t + delay_s + feedback_delay_s, estimator.target_kbps());
      }
      // One rung every 5 frames: down while the rung is over the target, up
      // while the one above fits.
      if (++frames_at_rung >= 5) {
        const double rate = kRungs[rung].kbps / kRungs[rung].every;
        if (rate > 1.05 * followed_kbps && rung + 1 < kRungs.size()) {
          ++rung, frames_at_rung = 0;
        } else if (rung > 0 &&
                   kRungs[rung - 1].kbps / kRungs[rung - 1].every < 0.9 * followed_kbps) {
          --rung, frames_at_rung = 0;
        }
      }
      if (tick % kRungs[rung].every != 0) continue;  // skipped by the encoder
      const double frame_bytes = kRungs[rung].kbps * 1000.0 / 8.0 / fps * (0.85 + 0.3 * unit(rng));
      ++seq;
      // The burst: every packet at once, each queued behind the last.
      bool lost = false;
      double last_out = 0;
      for (double left = frame_bytes; left > 0; left -= static_cast<double>(packet_bytes)) {
        const double bytes = std::min(left, static_cast<double>(packet_bytes));
        const double start = std::max(t, link_free_s);
        if (start - t > queue_s) {
          lost = true;  // the queue is full: this packet is dropped
          continue;
        }
        link_free_s = start + bytes * 8.0 / (capacity_kbps * 1000.0);
        last_out = link_free_s;
      }
      if (lost) continue;
      const double arrival = last_out + delay_s;
      estimator.OnFrame(seq, t, arrival, static_cast<size_t>(frame_bytes));
      if (estimator.FeedbackDue(arrival))
        on_their_way.emplace_back(arrival + feedback_delay_s, estimator.target_kbps());
    }
    return out;
  }
};

/// The first time at or after `from_s` when `test` holds, or -1.
double FirstTime(const std::vector<Sample>& run, double from_s,
                 const std::function<bool(const Sample&)>& test) {
  for (const Sample& s : run) {
    if (s.t_s >= from_s && test(s)) return s.t_s;
  }
  return -1;
}

}  // namespace

TEST_CASE("a step down in capacity is detected within 1 s and the target follows it down") {
  RateEstimator estimator;
  LinkRun link;
  link.capacity = [](double t) { return t < 20.0 ? 2000.0 : 500.0; };
  const std::vector<Sample> run = link.Run(estimator, 30.0);
  // Before the step the target had found the 2 Mbit/s link: near it, not far over.
  const auto before =
      std::find_if(run.begin(), run.end(), [](const Sample& s) { return s.t_s >= 19.9; });
  REQUIRE(before != run.end());
  INFO("target before the step " << before->target_kbps << " kbit/s");
  CHECK(before->target_kbps > 0.6 * 2000.0);
  CHECK(before->target_kbps < 1.3 * 2000.0);
  // After it: below the new capacity within a second, and it stays near it.
  const double below = FirstTime(run, 20.0, [](const Sample& s) { return s.target_kbps <= 500.0; });
  INFO("target below 500 kbit/s at " << below << " s");
  REQUIRE(below > 0);
  CHECK(below - 20.0 <= 1.0);
  for (const Sample& s : run) {
    if (s.t_s >= 25.0) {
      INFO("at " << s.t_s << " s the target is " << s.target_kbps);
      CHECK(s.target_kbps < 1.3 * 500.0);
      CHECK(s.target_kbps > 0.4 * 500.0);
    }
  }
}

TEST_CASE("a link faster than the video: the target climbs to the most and is never cut") {
  RateEstimatorConfig config;
  config.max_kbps = 3000.0;
  RateEstimator estimator(config);
  LinkRun link;
  link.capacity = [](double) { return 10000.0; };
  link.jitter_s = 0.004;  // a jittery but uncongested link
  const std::vector<Sample> run = link.Run(estimator, 40.0);
  CHECK(estimator.decreases() == 0);
  CHECK(run.back().target_kbps == Approx(3000.0));
  CHECK(estimator.usage() != LinkUsage::kOveruse);
}

TEST_CASE(
    "a steady link the video fills: the target stays in a band around the capacity, no "
    "oscillation") {
  RateEstimator estimator;
  LinkRun link;
  link.capacity = [](double) { return 1500.0; };
  const std::vector<Sample> run = link.Run(estimator, 60.0);
  double low = 1e9, high = 0;
  for (const Sample& s : run) {
    if (s.t_s < 20.0) continue;
    low = std::min(low, s.target_kbps);
    high = std::max(high, s.target_kbps);
  }
  INFO("target between " << low << " and " << high << " kbit/s; " << estimator.decreases()
                         << " cuts");
  CHECK(low > 0.6 * 1500.0);
  CHECK(high < 1.2 * 1500.0);
  // AIMD probes the capacity now and then; it does not saw at every frame.
  CHECK(estimator.decreases() <= 20);
}

TEST_CASE("loss without a queue: the loss-based estimate cuts the target") {
  RateEstimator estimator;
  LinkRun link;
  link.capacity = [](double) { return 10000.0; };
  link.loss = 0.3;
  const std::vector<Sample> run = link.Run(estimator, 10.0);
  CHECK(estimator.loss_share() > 0.15);
  CHECK(estimator.target_kbps() < RateEstimatorConfig{}.start_kbps);
  CHECK(estimator.decreases() == 0);  // the delay-based estimate saw no queue
}

TEST_CASE("targets reach the vehicle at most ten times a second") {
  RateEstimator estimator;
  int due = 0;
  for (int i = 0; i < 300; ++i) {
    const double t = i / 300.0;  // 300 frames within a second
    estimator.OnFrame(static_cast<uint64_t>(i), t, t + 0.02, 4000);
    if (estimator.FeedbackDue(t + 0.02)) ++due;
  }
  CHECK(due >= 9);
  CHECK(due <= 11);
}

TEST_CASE("the estimator's configuration is checked") {
  RateEstimatorConfig c;
  c.min_kbps = 0;
  CHECK_THROWS_WITH(RateEstimator(c), Catch::Contains("min_kbps"));
  c = {};
  c.max_kbps = 10;
  CHECK_THROWS_WITH(RateEstimator(c), Catch::Contains("max_kbps"));
  c = {};
  c.feedback_period_s = 0;
  CHECK_THROWS_WITH(RateEstimator(c), Catch::Contains("feedback_period_s"));
}

namespace {

/// The receiving side's configuration (mediator's VideoReceiver): start at
/// the most, so a link that carries the camera's own rate never changes it.
RateEstimatorConfig ReceiverConfig() {
  RateEstimatorConfig c;
  c.max_kbps = 20000.0;
  c.start_kbps = c.max_kbps;
  return c;
}

}  // namespace

TEST_CASE("bursty JPEG frames on a 1 Mbit/s link: the target settles within 30 % of the capacity") {
  // Issue 24: a 25 kB frame is one burst that takes 200 ms to pass at
  // 1 Mbit/s; the target must still come down to the link and stay there.
  for (const size_t packet_bytes : {size_t{64000}, size_t{1200}}) {
    DYNAMIC_SECTION("packets of up to " << packet_bytes << " bytes") {
      RateEstimator estimator(ReceiverConfig());
      BurstyJpegRun link;
      link.packet_bytes = packet_bytes;
      const std::vector<Sample> run = link.Run(estimator, 60.0);
      double low = 1e9, high = 0;
      for (const Sample& s : run) {
        if (s.t_s < 20.0) continue;
        low = std::min(low, s.target_kbps);
        high = std::max(high, s.target_kbps);
      }
      INFO("target between " << low << " and " << high << " kbit/s after 20 s; last "
                             << run.back().target_kbps << "; received " << estimator.received_kbps()
                             << "; " << estimator.decreases() << " cuts");
      CHECK(low >= 0.7 * 1000.0);
      CHECK(high <= 1.3 * 1000.0);
    }
  }
}

TEST_CASE(
    "a sender that pauses (its camera or host stalls, no frame lost): the silence's cuts are "
    "undone when it resumes; frames lost in a silence keep them") {
  RateEstimator estimator(ReceiverConfig());
  uint64_t seq = 0;
  double t = 0.0;
  for (; t < 2.0; t += 1.0 / 30.0) estimator.OnFrame(++seq, t, t + 0.02, 4000);
  const double before = estimator.target_kbps();
  const auto silence = [&](double from, double seconds) {
    for (double now = from; now < from + seconds; now += 0.1) estimator.OnSilence(now);
  };
  silence(t, 2.5);
  const double halved = estimator.target_kbps();
  CHECK(halved <= before / 4);  // two halvings, a second apart
  t += 2.5;
  estimator.OnFrame(++seq, t, t + 0.02, 4000);  // the next number: nothing was lost
  CHECK(estimator.target_kbps() == Approx(before));
  CHECK(estimator.FeedbackDue(t + 0.02));  // and the vehicle is told at once

  silence(t, 2.5);
  const double cut = estimator.target_kbps();
  seq += 40;  // forty frames sent in the silence never came: the link's
  t += 2.5;
  estimator.OnFrame(++seq, t, t + 0.02, 4000);
  CHECK(estimator.target_kbps() <= cut);
}
