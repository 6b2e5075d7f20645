// The camera streamer takes video feedback (key frame requests, the target
// bitrate) from the participant that owns the vehicle only: another
// participant on the domain cannot hold its video at the lowest rung, even
// naming the owner's session.
#include <atomic>
#include <catch2/catch.hpp>
#include <memory>
#include <mutex>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/camera_streamer.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

/// Another participant on the domain, sending video feedback as `session`.
struct FeedbackSender {
  FeedbackSender(const LinkConfig& config, const char* name)
      : participant(config, name),
        writer(participant, link::TopicName("robot1", "video_feedback"), link::Profile::kState) {}
  void Send(uint64_t session, uint32_t target_kbps, bool key_frame_request) {
    msg::VideoFeedback f;
    f.seq(++seq);
    f.sent_ns(MonotonicNs());
    f.session(session);
    f.target_kbps(target_kbps);
    f.key_frame_request(key_frame_request);
    writer.Write(f);
  }
  link::Participant participant;
  link::VideoFeedbackWriter writer;
  uint64_t seq = 0;
};

}  // namespace

TEST_CASE(
    "video feedback is followed from the owner's participant only, anybody's while nobody owns the "
    "vehicle") {
  // Writer `entity` of participant `participant` (the GUID prefix's last byte).
  const auto writer = [](uint8_t participant, uint8_t entity) {
    link::WriterId id;
    id.guid[0] = 0x01;
    id.guid[1] = 0x0f;
    id.guid[11] = participant;
    id.guid[15] = entity;
    return id;
  };
  const link::WriterId owner = writer(1, 3);
  CHECK(video::FeedbackFromOwner(owner, writer(1, 7)));  // the owner's run: its feedback writer
  CHECK_FALSE(video::FeedbackFromOwner(owner, writer(9, 7)));
  CHECK_FALSE(video::FeedbackFromOwner(owner, writer(9, 3)));
  CHECK(video::FeedbackFromOwner({}, writer(9, 7)));
}

TEST_CASE(
    "video feedback from a participant that does not own the vehicle is refused and counted; the "
    "owner's works") {
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  LinkConfig link;
  link.domain_id = test::UniqueDomain(81);
  CameraConfig camera;
  camera.codec = CameraCodec::kH264;
  link::Participant vehicle(link, "test-vehicle");
  FeedbackSender stranger(link, "test-stranger");
  FeedbackSender op(link, "test-operator");
  // The command writer the vehicle obeys (CommandOwner): one of the
  // operator's participant (its feedback writer shares the GUID prefix).
  std::mutex mutex;
  link::WriterId owner = op.writer.id();
  owner.guid[15] ^= 0x40;  // another entity of the same participant
  video::CameraStreamer streamer(camera, std::make_unique<video::SyntheticSource>(track, camera),
                                 vehicle, "robot1", [&] {
                                   std::lock_guard lock(mutex);
                                   return owner;
                                 });

  // A stranger asks for the lowest bitrate and a key frame, naming the
  // owner's session (read off the wire), until the vehicle has heard it (a
  // sample sent before discovery is not received).
  REQUIRE(test::WaitFor(
      [&] {
        stranger.Send(1111, 100, true);
        return streamer.Counters().feedback_refused >= 3;
      },
      30.0));
  video::CameraCounters c = streamer.Counters();
  CHECK(c.target_kbps == 0);         // the target is not the stranger's
  CHECK(c.key_frame_requests == 0);  // nor is a key frame forced
  // Nor with any other session.
  const uint64_t refused = c.feedback_refused;
  REQUIRE(test::WaitFor(
      [&] {
        stranger.Send(0, 100, true);
        return streamer.Counters().feedback_refused > refused;
      },
      30.0));
  CHECK(streamer.Counters().target_kbps == 0);

  // The owner's feedback still works.
  REQUIRE(test::WaitFor(
      [&] {
        op.Send(1111, 700, true);
        return streamer.Counters().target_kbps == 700 && streamer.Counters().key_frame_requests > 0;
      },
      30.0));
  c = streamer.Counters();
  CHECK(c.target_kbps == 700);
  CHECK(c.key_frame_requests > 0);

  // Another owner (the first released the vehicle): the old one's feedback is refused now.
  {
    std::lock_guard lock(mutex);
    owner = stranger.writer.id();
  }
  const uint64_t before = streamer.Counters().feedback_refused;
  REQUIRE(test::WaitFor(
      [&] {
        op.Send(1111, 200, false);
        return streamer.Counters().feedback_refused > before;
      },
      30.0));
  CHECK(streamer.Counters().target_kbps == 700);
}

TEST_CASE("video feedback while nobody owns the vehicle is taken from any participant") {
  // Nothing to protect yet (no operator drives it), and a vehicle only
  // watched, never commanded, still follows the link.
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  LinkConfig link;
  link.domain_id = test::UniqueDomain(82);
  CameraConfig camera;
  camera.codec = CameraCodec::kJpeg;
  link::Participant vehicle(link, "test-vehicle");
  video::CameraStreamer streamer(camera, std::make_unique<video::SyntheticSource>(track, camera),
                                 vehicle, "robot1", [] { return link::WriterId{}; });
  FeedbackSender op(link, "test-operator");
  REQUIRE(test::WaitFor(
      [&] {
        op.Send(4444, 600, false);
        return streamer.Counters().target_kbps == 600;
      },
      30.0));
  CHECK(streamer.Counters().feedback_refused == 0);
}
