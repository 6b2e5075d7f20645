#pragma once
/// @file What the video benches share (`haptel bench video`'s capacity
/// schedule, `haptel bench fleet`'s video): a lossless recording of the
/// synthetic camera's lap frames that a real haptel-vehicle plays as its
/// file camera, and SSIM of sampled decoded pictures against the frames
/// they were made from.
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <utility>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/video/image_quality.hpp"

namespace haptel::bench {

/// Writes `frames` losslessly (FFV1) for the vehicle's file camera; throws
/// std::runtime_error naming the file when it cannot.
void WriteLosslessSource(const std::filesystem::path& file, const std::vector<cv::Mat>& frames,
                         double rate_hz);

/// `vehicle`'s file with the camera playing `source` (looping) through
/// `codec`, and the world as an absolute path: the copy lives elsewhere.
void WriteVehicleFileWithSource(const VehicleConfig& vehicle, CameraCodec codec,
                                const std::filesystem::path& source,
                                const std::filesystem::path& out);

/// Compares sampled pictures with their source frames on a thread of its
/// own, so the measuring loop never waits for an SSIM; at most a few wait
/// (more are not taken: a sample, not every picture).
class SsimWorker {
 public:
  /// How a picture of another size than the sources is compared.
  enum class Size {
    kSource,   ///< scaled up to the source's, as the view shows a half-resolution rung
    kPicture,  ///< at its own: the source scaled down (a fleet's tile, at the size it is sent)
  };
  SsimWorker(const std::vector<cv::Mat>& sources, double rate_hz, size_t phases,
             Size size = Size::kSource)
      : sources_(sources), rate_hz_(rate_hz), size_(size), sum_(phases, 0.0), count_(phases, 0) {
    for (const cv::Mat& s : sources_) small_.push_back(Small(s));
    thread_ = std::thread([this] { Loop(); });
  }
  ~SsimWorker() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  /// False when the queue is full (the sample is skipped).
  bool Offer(std::shared_ptr<const cv::Mat> picture, int64_t capture_wall_ns, int phase) {
    {
      std::lock_guard lock(mutex_);
      if (queue_.size() >= 4) return false;
      queue_.push_back({std::move(picture), capture_wall_ns, phase});
    }
    wake_.notify_one();
    return true;
  }
  /// Waits for the queue to empty, then the mean per phase (NaN: none) and the count.
  std::pair<double, int> Phase(int phase) {
    std::unique_lock lock(mutex_);
    idle_.wait(lock, [this] { return queue_.empty() && !busy_; });
    const int n = count_[static_cast<size_t>(phase)];
    return {n > 0 ? sum_[static_cast<size_t>(phase)] / n : std::nan(""), n};
  }

 private:
  struct Job {
    std::shared_ptr<const cv::Mat> picture;
    int64_t capture_wall_ns;
    int phase;
  };
  static cv::Mat Small(const cv::Mat& bgr) {
    cv::Mat gray, small;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    cv::resize(gray, small, cv::Size(80, 60), 0, 0, cv::INTER_AREA);
    small.convertTo(small, CV_32F);
    return small;
  }
  /// The source frame `picture` shows: between the last match and where
  /// the capture stamp puts it at the frame rate (a file camera plays each
  /// frame in turn, later than its rate on a loaded vehicle, never
  /// sooner), the closest by a small picture's difference; the whole loop
  /// before the first match.
  size_t Match(const cv::Mat& picture, int64_t capture_wall_ns) {
    const cv::Mat small = Small(picture);
    const auto n = static_cast<int64_t>(sources_.size());
    int64_t from = 0, to = n - 1;
    if (anchor_ns_ != 0) {
      const int64_t expected =
          anchor_index_ +
          static_cast<int64_t>(std::llround(NsToS(capture_wall_ns - anchor_ns_) * rate_hz_));
      from = std::min(anchor_index_, expected - 3);
      to = std::min(expected + 3, from + n - 1);
    }
    double best = 1e300;
    int64_t best_index = 0;
    for (int64_t i = from; i <= to; ++i) {
      const size_t k = static_cast<size_t>(((i % n) + n) % n);
      const double d = cv::norm(small, small_[k], cv::NORM_L2SQR);
      if (d < best) best = d, best_index = static_cast<int64_t>(k);
    }
    anchor_ns_ = capture_wall_ns;
    anchor_index_ = best_index;
    return static_cast<size_t>(best_index);
  }
  void Loop() {
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      Job job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
      lock.unlock();
      cv::Mat picture = *job.picture;
      const cv::Size source_size = sources_[0].size();
      double ssim = 0.0;
      if (picture.size() == source_size) {
        ssim = video::Ssim(sources_[Match(picture, job.capture_wall_ns)], picture);
      } else if (size_ == Size::kSource) {
        // A half-resolution rung (JPEG's ladder) is shown scaled up, as the view does.
        cv::resize(picture, picture, source_size, 0, 0, cv::INTER_LINEAR);
        ssim = video::Ssim(sources_[Match(picture, job.capture_wall_ns)], picture);
      } else {
        cv::Mat source;
        cv::resize(sources_[Match(picture, job.capture_wall_ns)], source, picture.size(), 0, 0,
                   cv::INTER_AREA);
        ssim = video::Ssim(source, picture);
      }
      lock.lock();
      sum_[static_cast<size_t>(job.phase)] += ssim;
      ++count_[static_cast<size_t>(job.phase)];
      busy_ = false;
      if (queue_.empty()) idle_.notify_all();
    }
  }

  const std::vector<cv::Mat>& sources_;
  std::vector<cv::Mat> small_;
  double rate_hz_;
  Size size_;
  int64_t anchor_ns_ = 0;
  int64_t anchor_index_ = 0;
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<Job> queue_;
  bool stop_ = false, busy_ = false;
  std::vector<double> sum_;
  std::vector<int> count_;
  std::thread thread_;
};

}  // namespace haptel::bench
