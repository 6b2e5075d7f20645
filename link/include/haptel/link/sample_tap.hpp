#pragma once
/// @file A tap on a participant's samples, for a session file
/// (record/session_recorder.hpp): every sample its writers send and its
/// readers take, as the CDR bytes that crossed the link. Nothing changes
/// on the wire; without a tap (the default) nothing is done.
///
/// The bytes: a writer's sample is serialized by the type's own type
/// support, as DDS serializes it to send it; a reader's, re-serialized
/// from the sample DDS decoded. Both are the bytes on the wire (Fast DDS
/// writes plain CDR, little-endian, with its 4-byte encapsulation header,
/// and decoding then encoding a sample gives those bytes back: the suite
/// checks it, tests/link/test_sample_tap.cpp).
#include <cstddef>
#include <cstdint>
#include <string>

namespace haptel::link {

enum class TapDirection { kSent, kReceived };

class SampleTap {
 public:
  virtual ~SampleTap() = default;
  /// A writer or reader of `topic` with DDS type `type_name` (e.g.
  /// "haptel::msg::TreadCommand") is made: its channel for OnSample, or -1
  /// not to tap it. Called on the thread that makes it.
  virtual int OnTopic(const std::string& topic, const std::string& type_name,
                      TapDirection direction) = 0;
  /// Whether `channel` wants the CDR bytes (false: OnSample gets the
  /// decoded sample alone, e.g. a video frame written in another schema).
  virtual bool WantsBytes(int channel) const = 0;
  /// One sample on `channel`, at `now_ns` (CLOCK_MONOTONIC), `sample` the
  /// typed message (of the channel's type), `cdr` its bytes (null without
  /// WantsBytes). Called on the writer's or the reader's thread (DDS's, for
  /// a reader): it must not block. Each channel has one producer at a time.
  virtual void OnSample(int channel, int64_t now_ns, const void* sample, const uint8_t* cdr,
                        size_t size) = 0;
};

}  // namespace haptel::link
