#include "haptel/replay/view_playback.hpp"

#include <SDL2/SDL.h>
#include <fastdds/rtps/common/SerializedPayload.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <thread>

#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/session/foxglovePubSubTypes.h"
#include "haptel/video/video_receiver.hpp"
#include "haptel/view/canvas.hpp"
#include "haptel/view/mp4_writer.hpp"

namespace haptel::replay {
namespace {

namespace channels = record::session;

/// Decoded pictures kept for the view frames that name them: a frame names
/// a picture received before it, usually the latest, but the live screen
/// may show one well behind the latest the file has: its receiver decodes
/// up to 15 frames behind their arrival (video_receiver.cpp's
/// kMaxQueuedH264), and after a dropped queue or a frame lost on the link
/// shows its last good picture, marked stale, until the next key frame
/// (the streamer sends one at least every second: 30 pictures, more while
/// its request waits on a loaded host). Pictures older than one a frame
/// named are let go at once (the screen never goes back), so these are kept
/// only while the screen lags; 96 (about 3 s at 30 fps) is the most.
constexpr size_t kPicturesKept = 96;
/// How far before a sought time the video is read again for its key frame
/// (the streamer sends one at least every second).
constexpr uint64_t kKeyFrameBackNs = 3'000'000'000;
/// How long (log time) a view frame waits for its picture to be filed.
constexpr uint64_t kPictureWaitNs = 200'000'000;

/// Whether an H.264 Annex B access unit decodes alone: it holds an IDR
/// slice (NAL type 5) or a sequence parameter set (7), as every key frame
/// the streamer sends does.
bool AnnexBKeyFrame(const uint8_t* data, size_t size) {
  for (size_t i = 0; i + 3 < size; ++i) {
    if (data[i] == 0 && data[i + 1] == 0 && data[i + 2] == 1) {
      const int type = data[i + 3] & 0x1f;
      if (type == 5 || type == 7) return true;
      i += 2;
    }
  }
  return false;
}

int64_t MonotonicWallNs() { return RealMonotonicNs(); }

uint64_t FromS(const ViewPlayback& playback, double from_s) {
  if (!(from_s > 0)) return playback.start_ns();
  return std::min(playback.end_ns(),
                  playback.start_ns() + static_cast<uint64_t>(std::llround(from_s * 1e9)));
}

}  // namespace

ViewPlayback::ViewPlayback(const mcap::Reader& reader) : reader_(reader) {
  const std::string file = reader.path().string();
  for (const auto& [id, channel] : reader.channels()) {
    const auto schema = reader.schemas().find(channel.schema_id);
    const std::string schema_name = schema != reader.schemas().end() ? schema->second.name : "";
    if (channel.topic == view::kViewFrameTopic && view_channel_ == 0) {
      view_channel_ = id;
    } else if (video_channel_ == 0 && (schema_name == channels::kCompressedVideoSchema ||
                                       schema_name == channels::kCompressedImageSchema)) {
      video_channel_ = id;
      jpeg_ = schema_name == channels::kCompressedImageSchema;
    }
  }
  if (view_channel_ == 0 && video_channel_ == 0) {
    throw cli::InputError(
        file + ": no view channel (" + view::kViewFrameTopic + ") and no video channel (" +
        std::string(channels::kCompressedVideoSchema) + " or " +
        std::string(channels::kCompressedImageSchema) +
        "): nothing to replay; haptel replay --info " + file + " lists what it holds");
  }
  if (view_channel_ != 0) topics_.push_back(view::kViewFrameTopic);
  if (video_channel_ != 0) topics_.push_back(reader.channels().at(video_channel_).topic);
  // The set-up, said once at the view's start.
  reader.ForEachMessage(0, UINT64_MAX, {view::kViewSetupTopic}, [&](const mcap::MessageView& m) {
    try {
      setup_ = view::DecodeViewSetup(m.data, m.size);
    } catch (const view::ViewRecordError& e) {
      throw cli::InputError(file + ": " + e.what());
    }
  });
  const mcap::Statistics& stats = reader.statistics();
  start_ns_ = stats.message_start_time_ns;
  end_ns_ = std::max(stats.message_end_time_ns, start_ns_);
  decoder_ = video::MakeVideoDecoder(jpeg_ ? CameraCodec::kJpeg : CameraCodec::kH264);
}

ViewPlayback::~ViewPlayback() = default;

void ViewPlayback::OnVideo(const mcap::MessageView& message) {
  foxglove::CompressedVideoPubSubType type;  // CompressedImage has the same fields in order
  foxglove::CompressedVideo picture;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      static_cast<uint32_t>(std::max<size_t>(message.size, 1)));
  std::memcpy(payload.data, message.data, message.size);
  payload.length = static_cast<uint32_t>(message.size);
  bool decoded = false;
  try {
    decoded = type.deserialize(&payload, &picture);
  } catch (const std::exception&) {
    decoded = false;  // Fast CDR throws on a short buffer
  }
  if (!decoded) {
    ++pictures_undecoded_;
    return;
  }
  const std::vector<uint8_t>& bytes = picture.data();
  video::EncodedFrameView encoded;
  encoded.data = bytes.data();
  encoded.size = bytes.size();
  encoded.seq = message.sequence;
  encoded.key_frame = jpeg_ || AnnexBKeyFrame(bytes.data(), bytes.size());
  // After a seek the pictures start at a key frame: those before it cannot
  // decode (their references were not read).
  if (awaiting_key_frame_ && !encoded.key_frame) return;
  awaiting_key_frame_ = false;
  cv::Mat image;
  const video::DecodeResult result = decoder_->DecodeFrame(encoded, image);
  if (result != video::DecodeResult::kPicture) {
    if (result == video::DecodeResult::kCorrupt) ++pictures_undecoded_;
    return;
  }
  Picture p;
  p.capture_wall_ns =
      static_cast<int64_t>(picture.timestamp().sec()) * 1'000'000'000 + picture.timestamp().nsec();
  p.frame.image = std::make_shared<const cv::Mat>(std::move(image));
  p.frame.id = next_picture_id_++;
  p.frame.capture_wall_ns = p.capture_wall_ns;
  pictures_.push_back(std::move(p));
  // Without a view channel each picture is shown alone, as it comes.
  const size_t kept = view_channel_ != 0 ? kPicturesKept : 1;
  while (pictures_.size() > kept) pictures_.pop_front();
}

const video::Frame* ViewPlayback::PictureFor(int64_t capture_wall_ns) {
  if (capture_wall_ns == 0) return nullptr;  // the live screen had no picture yet
  for (auto it = pictures_.rbegin(); it != pictures_.rend(); ++it) {
    if (it->capture_wall_ns != capture_wall_ns) continue;
    // The live screen never shows an older picture than this one again.
    pictures_.erase(pictures_.begin(), std::prev(it.base()));
    return &pictures_.front().frame;
  }
  ++pictures_missing_;
  return pictures_.empty() ? nullptr : &pictures_.back().frame;
}

void ViewPlayback::Play(
    uint64_t from_ns, uint64_t to_ns,
    const std::function<void(const view::ViewFrame& frame, uint64_t log_ns)>& on_frame) {
  if (to_ns <= from_ns) return;
  uint64_t read_from = from_ns;
  if (played_to_ns_ == 0 || from_ns != played_to_ns_) {
    // A seek: the decoder starts again at the key frame before `from_ns`.
    decoder_ = video::MakeVideoDecoder(jpeg_ ? CameraCodec::kJpeg : CameraCodec::kH264);
    pictures_.clear();
    awaiting_key_frame_ = true;
    read_from = from_ns > kKeyFrameBackNs ? from_ns - kKeyFrameBackNs : 0;
  }
  played_to_ns_ = to_ns;
  // A view frame waits for its picture: the run files a picture when the
  // link hands it over, which may be a few milliseconds after the view,
  // whose receiver had it first, drew it.
  const auto emit_ready = [&](uint64_t now_ns, bool all) {
    while (!pending_.empty()) {
      auto& [frame, log_ns] = pending_.front();
      const int64_t stamp = frame.video_capture_wall_ns;
      const bool ready = all || stamp == 0 || Decoded(stamp) ||
                         (!pictures_.empty() && pictures_.back().capture_wall_ns >= stamp) ||
                         now_ns > log_ns + kPictureWaitNs;
      if (!ready) return;
      Show(frame);
      on_frame(frame, log_ns);
      pending_.pop_front();
    }
  };
  reader_.ForEachMessage(read_from, to_ns, topics_, [&](const mcap::MessageView& m) {
    const bool shown = m.log_time_ns >= from_ns;
    if (m.channel->id == video_channel_) {
      OnVideo(m);
      emit_ready(m.log_time_ns, false);
      if (!shown || view_channel_ != 0 || pictures_.empty()) return;
      // No view channel: each picture alone on the screen.
      frame_.model.shapes.clear();
      frame_.model.video = pictures_.back().frame;
      frame_.video_capture_wall_ns = pictures_.back().capture_wall_ns;
      frame_.view_t_s = static_cast<double>(m.log_time_ns - start_ns_) * 1e-9;
      frame_.copies = 1;
      on_frame(frame_, m.log_time_ns);
      return;
    }
    if (!shown) return;
    try {
      view::DecodeViewFrame(m.data, m.size, frame_);
    } catch (const view::ViewRecordError& e) {
      throw cli::InputError(reader_.path().string() + ": " + e.what());
    }
    pending_.emplace_back(frame_, m.log_time_ns);
    emit_ready(m.log_time_ns, false);
  });
  emit_ready(to_ns, true);
}

bool ViewPlayback::Decoded(int64_t capture_wall_ns) const {
  return std::any_of(pictures_.begin(), pictures_.end(),
                     [&](const Picture& p) { return p.capture_wall_ns == capture_wall_ns; });
}

void ViewPlayback::Show(view::ViewFrame& frame) {
  const video::Frame* picture = PictureFor(frame.video_capture_wall_ns);
  frame.model.video = picture != nullptr ? *picture : video::Frame{};
  if (picture != nullptr && frame.video_stale) {
    // Marked as the live receiver marked it, once per picture.
    if (stale_of_id_ != picture->id) {
      stale_of_id_ = picture->id;
      stale_ = *picture;
      stale_.image = std::make_shared<const cv::Mat>(video::MarkStale(*picture->image));
      stale_.id = next_picture_id_++;
      stale_.stale = true;
    }
    frame.model.video = stale_;
  }
}

ReplayClock::ReplayClock(uint64_t start_ns, uint64_t end_ns, double speed, double frame_s)
    : start_ns_(start_ns),
      end_ns_(std::max(end_ns, start_ns)),
      speed_(speed > 0 ? speed : 1.0),
      frame_s_(frame_s > 0 ? frame_s : 1.0 / 30.0),
      anchor_ns_(start_ns) {}

uint64_t ReplayClock::Now(int64_t wall_ns) const {
  if (paused_) return anchor_ns_;
  const double ahead = static_cast<double>(wall_ns - anchor_wall_ns_) * speed_;
  const double t = static_cast<double>(anchor_ns_) + std::max(0.0, ahead);
  return std::min(end_ns_, static_cast<uint64_t>(t));
}

void ReplayClock::Anchor(uint64_t at_ns, int64_t wall_ns) {
  anchor_ns_ = std::clamp(at_ns, start_ns_, end_ns_);
  anchor_wall_ns_ = wall_ns;
}

void ReplayClock::TogglePause(int64_t wall_ns) {
  Anchor(Now(wall_ns), wall_ns);
  paused_ = !paused_;
}

void ReplayClock::Step(int frames, int64_t wall_ns) {
  const auto now = static_cast<double>(Now(wall_ns));
  const double to = std::max(0.0, now + frames * frame_s_ * 1e9);
  paused_ = true;
  Anchor(static_cast<uint64_t>(to), wall_ns);
}

void ReplayClock::Seek(double seconds, int64_t wall_ns) {
  const double to = std::max(0.0, static_cast<double>(Now(wall_ns)) + seconds * 1e9);
  Anchor(static_cast<uint64_t>(to), wall_ns);
}

void ReplayClock::Home(int64_t wall_ns) { Anchor(start_ns_, wall_ns); }

ReplayReport ReadReplay(ViewPlayback& playback, double from_s) {
  ReplayReport report;
  report.has_view = playback.has_view();
  uint64_t last_picture = 0;
  playback.Play(FromS(playback, from_s), playback.end_ns() + 1,
                [&](const view::ViewFrame& frame, uint64_t) {
                  ++report.frames;
                  if (frame.model.video.id != 0 && frame.model.video.id != last_picture) {
                    last_picture = frame.model.video.id;
                    ++report.pictures;
                  }
                });
  report.pictures_missing = playback.pictures_missing();
  report.pictures_undecoded = playback.pictures_undecoded();
  report.duration_s = static_cast<double>(playback.end_ns() - playback.start_ns()) * 1e-9;
  return report;
}

ReplayReport RenderReplayMp4(ViewPlayback& playback, double from_s,
                             const std::filesystem::path& mp4) {
  const view::ViewSetup& setup = playback.setup();
  view::ViewOptions options;
  options.mode = view::ViewMode::kOffscreen;
  options.width = setup.width;
  options.height = setup.height;
  options.screen = setup.screen;
  options.title = setup.title;
  view::Canvas canvas(options);
  if (mp4.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(mp4.parent_path(), ec);
  }
  view::Mp4Writer writer(mp4, setup.width, setup.height, setup.record_fps);
  view::Renderer& renderer = canvas.renderer();
  ReplayReport report;
  report.has_view = playback.has_view();
  view::ViewModel model;
  model.shapes.reserve(256);
  cv::Mat bgr;
  uint64_t last_picture = 0;
  playback.Play(FromS(playback, from_s), playback.end_ns() + 1,
                [&](const view::ViewFrame& frame, uint64_t) {
                  // A frame the live encoder dropped whole is not in its MP4.
                  if (writer.failed() || frame.copies <= 0) return;
                  model = frame.model;
                  model.map = setup.map;
                  renderer.Draw(model, frame.view_t_s);
                  renderer.ReadPixels(bgr);
                  for (int i = 0; i < frame.copies; ++i) {
                    if (writer.Write(bgr)) ++report.mp4_frames;
                  }
                  ++report.frames;
                  if (frame.model.video.id != 0 && frame.model.video.id != last_picture) {
                    last_picture = frame.model.video.id;
                    ++report.pictures;
                  }
                });
  if (!writer.Close()) throw view::ViewError(writer.error());
  report.pictures_missing = playback.pictures_missing();
  report.pictures_undecoded = playback.pictures_undecoded();
  report.duration_s = static_cast<double>(playback.end_ns() - playback.start_ns()) * 1e-9;
  return report;
}

namespace {

/// The window's source and keys: both called on the view thread, so the
/// clock and the playback need no lock.
class WindowReplay final : public view::ViewSource, public view::EventSink {
 public:
  WindowReplay(ViewPlayback& playback, uint64_t from_ns, double speed)
      : playback_(playback),
        clock_(playback.start_ns(), playback.end_ns(), speed,
               1.0 / std::max(1.0, playback.setup().record_fps)) {
    clock_.Seek(static_cast<double>(from_ns - playback.start_ns()) * 1e-9, MonotonicWallNs());
  }

  void Fill(view::ViewModel& model) override {
    const uint64_t now = clock_.Now(MonotonicWallNs());
    if (now != shown_ns_) {
      // Forward: read on from where the last frame was; back (a step, a
      // seek, Home): from the frame before.
      const auto frame_ns =
          static_cast<uint64_t>(1e9 / std::max(1.0, playback_.setup().record_fps));
      const bool on = shown_ns_ != 0 && now > shown_ns_;
      const uint64_t from = on ? shown_ns_ : (now > 2 * frame_ns ? now - 2 * frame_ns : 0);
      playback_.Play(from, now, [&](const view::ViewFrame& frame, uint64_t) {
        latest_ = frame.model;
        ++report_.frames;
        if (frame.model.video.id != 0 && frame.model.video.id != last_picture_) {
          last_picture_ = frame.model.video.id;
          ++report_.pictures;
        }
      });
      shown_ns_ = now;
    }
    model = latest_;
    model.map = playback_.setup().map;
  }

  void OnEvent(const SDL_Event& event) override {
    const int64_t wall = MonotonicWallNs();
    if (event.type == SDL_QUIT) quit_.store(true);
    if (event.type != SDL_KEYDOWN) return;
    switch (event.key.keysym.sym) {
      case SDLK_SPACE:
        clock_.TogglePause(wall);
        break;
      case SDLK_PERIOD:
        clock_.Step(1, wall);
        break;
      case SDLK_COMMA:
        clock_.Step(-1, wall);
        break;
      case SDLK_RIGHT:
        clock_.Seek(5.0, wall);
        break;
      case SDLK_LEFT:
        clock_.Seek(-5.0, wall);
        break;
      case SDLK_HOME:
        clock_.Home(wall);
        break;
      case SDLK_ESCAPE:
      case SDLK_q:
        quit_.store(true);
        break;
      default:
        break;
    }
  }

  bool quit() const { return quit_.load(); }
  ReplayReport report() const { return report_; }

 private:
  ViewPlayback& playback_;
  ReplayClock clock_;
  uint64_t shown_ns_ = 0;
  view::ViewModel latest_;
  uint64_t last_picture_ = 0;
  ReplayReport report_;
  std::atomic<bool> quit_{false};
};

}  // namespace

ReplayReport PlayReplayWindow(ViewPlayback& playback, double from_s, double speed,
                              const std::atomic<bool>& interrupted) {
  const view::ViewSetup& setup = playback.setup();
  view::ViewOptions options;
  options.mode = view::ViewMode::kWindow;
  options.width = setup.width;
  options.height = setup.height;
  options.rate_hz = setup.rate_hz;
  options.screen = setup.screen;
  options.title = "Haptel replay - " + playback.file();
  if (!view::View::DisplayAvailable()) {
    throw view::ViewError(
        "no display for a window ($DISPLAY is not set or not reachable); use --mp4 OUT.mp4 to "
        "render offscreen, or --view none");
  }
  WindowReplay replay(playback, FromS(playback, from_s), speed);
  view::View view(options, replay, &replay);
  // The window stays at the last frame once the record ends, until closed.
  while (!replay.quit() && !interrupted.load()) SleepUntilNs(MonotonicNs() + 20'000'000);
  view.Stop();
  ReplayReport report = replay.report();
  report.has_view = playback.has_view();
  report.pictures_missing = playback.pictures_missing();
  report.pictures_undecoded = playback.pictures_undecoded();
  report.duration_s = static_cast<double>(playback.end_ns() - playback.start_ns()) * 1e-9;
  return report;
}

}  // namespace haptel::replay
