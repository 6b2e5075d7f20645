#include "bare_loop.hpp"

#include "haptel/core/clock.hpp"
#include "haptel/core/periodic_thread.hpp"

namespace haptel::bench {

BareLoop MeasureBareLoop(double rate_hz, int realtime_priority, double seconds) {
  return MeasureBareLoopWhile(rate_hz, realtime_priority,
                              [seconds] { SleepUntilNs(MonotonicNs() + SToNs(seconds + 0.2)); });
}

BareLoop MeasureBareLoopWhile(double rate_hz, int realtime_priority,
                              const std::function<void()>& work) {
  PeriodicThread::Options o;
  o.name = "bare";
  o.rate_hz = rate_hz;
  o.realtime_priority = realtime_priority;
  PeriodicThread loop(o, [](int64_t) {});
  loop.Start();
  work();
  loop.Stop();
  BareLoop r;
  r.stats = loop.Stats();
  const Histogram& h = loop.period_histogram();
  r.bin_us = h.bin_width_us();
  for (int i = 0; i <= h.bins(); ++i) r.histogram.push_back(static_cast<double>(h.BinCount(i)));
  return r;
}

}  // namespace haptel::bench
