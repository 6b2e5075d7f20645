// The link-rate estimator on synthetic arrival traces: a sender that follows
// the estimator's target through a bottleneck of the test's own (a
// drop-tail queue served at the link's capacity, a propagation delay, a
// little jitter), in simulated time.
#include <catch2/catch.hpp>

#include <algorithm>
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
      if (estimator.FeedbackDue(arrival)) on_their_way.emplace_back(arrival + feedback_delay_s, estimator.target_kbps());
    }
    return out;
  }
};

/// The first time at or after `from_s` when `test` holds, or -1.
double FirstTime(const std::vector<Sample>& run, double from_s, const std::function<bool(const Sample&)>& test) {
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
  const auto before = std::find_if(run.begin(), run.end(), [](const Sample& s) { return s.t_s >= 19.9; });
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

TEST_CASE("a steady link the video fills: the target stays in a band around the capacity, no oscillation") {
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
  INFO("target between " << low << " and " << high << " kbit/s; " << estimator.decreases() << " cuts");
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
