// An OpenXR head-mounted display's head pose (head_source.hpp), through the
// OpenXR loader Debian ships (libopenxr-loader1). Headless where the runtime
// offers XR_MND_headless: no graphics binding, no frames submitted; the
// view space is located against the local space on a thread of its own at
// the frame loop's pace, and the latest pose is handed over in a seqlock.
#include <openxr/openxr.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "haptel/core/seqlock.hpp"
#include "haptel/view/head_source.hpp"

namespace haptel::view {

namespace {

/// An OpenXR struct zeroed but for its type (the API's way: `next` null).
template <typename T>
T Xr(XrStructureType type) {
  T t{};
  t.type = type;
  return t;
}

std::string ResultText(XrResult r) {
  switch (r) {
    case XR_ERROR_RUNTIME_UNAVAILABLE:
      return "XR_ERROR_RUNTIME_UNAVAILABLE";  // no active runtime installed (e.g. Monado)
    case XR_ERROR_RUNTIME_FAILURE:
      return "XR_ERROR_RUNTIME_FAILURE";
    case XR_ERROR_FORM_FACTOR_UNSUPPORTED:
      return "XR_ERROR_FORM_FACTOR_UNSUPPORTED: the runtime has no head-mounted display";
    case XR_ERROR_FORM_FACTOR_UNAVAILABLE:
      return "XR_ERROR_FORM_FACTOR_UNAVAILABLE: the head-mounted display is not connected";
    default:
      return "XrResult " + std::to_string(static_cast<int>(r));
  }
}

/// The pose as the reader takes it.
struct TrackedHead {
  double pan = 0.0;
  double tilt = 0.0;
  bool tracked = false;  ///< the runtime tracks the head's orientation now
  bool lost = false;     ///< the session ended under us (it does not come back)
};

class OpenXrHead : public HeadSource {
 public:
  OpenXrHead(XrInstance instance, XrSession session, XrSpace view, XrSpace local)
      : instance_(instance), session_(session), view_(view), local_(local) {
    thread_ = std::thread([this] { Run(); });
  }
  ~OpenXrHead() override {
    stop_.store(true);
    thread_.join();
    xrDestroySpace(view_);
    xrDestroySpace(local_);
    xrDestroySession(session_);
    xrDestroyInstance(instance_);
  }

  HeadPose Update(double, const interfaces::InputState&) override {
    const TrackedHead now = head_.Load();
    lost_ = now.lost || (seen_tracked_ && !now.tracked);
    seen_tracked_ = seen_tracked_ || now.tracked;
    if (now.tracked && !now.lost) held_ = {now.pan, now.tilt};
    return held_;  // lost: still where it last looked
  }
  const char* Notice() const override {
    return lost_ ? "head tracker lost (OpenXR): the camera holds still" : nullptr;
  }
  HeadSourceKind kind() const override { return HeadSourceKind::kOpenXr; }

 private:
  void Run() {
    bool running = false;
    TrackedHead out;
    while (!stop_.load()) {
      auto event = Xr<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
      while (xrPollEvent(instance_, &event) == XR_SUCCESS) {
        if (event.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED) {
          const auto& changed = reinterpret_cast<const XrEventDataSessionStateChanged&>(event);
          if (changed.state == XR_SESSION_STATE_READY && !running) {
            auto begin = Xr<XrSessionBeginInfo>(XR_TYPE_SESSION_BEGIN_INFO);
            begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
            running = XR_SUCCEEDED(xrBeginSession(session_, &begin));
          } else if (changed.state == XR_SESSION_STATE_STOPPING ||
                     changed.state == XR_SESSION_STATE_LOSS_PENDING ||
                     changed.state == XR_SESSION_STATE_EXITING) {
            out.lost = true;
            out.tracked = false;
            head_.Store(out);
            if (running) xrEndSession(session_);
            running = false;
          }
        } else if (event.type == XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING) {
          out.lost = true;
          out.tracked = false;
          head_.Store(out);
        }
        event = Xr<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
      }
      if (!running) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      // The frame loop paces this thread and gives the time to locate at.
      auto frame = Xr<XrFrameState>(XR_TYPE_FRAME_STATE);
      auto wait = Xr<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
      if (XR_FAILED(xrWaitFrame(session_, &wait, &frame))) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      auto begin = Xr<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
      xrBeginFrame(session_, &begin);
      auto where = Xr<XrSpaceLocation>(XR_TYPE_SPACE_LOCATION);
      const bool located =
          XR_SUCCEEDED(xrLocateSpace(view_, local_, frame.predictedDisplayTime, &where));
      out.tracked = located && (where.locationFlags & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT) &&
                    (where.locationFlags & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT);
      if (out.tracked) {
        const XrQuaternionf& q = where.pose.orientation;
        const HeadPose p = HeadPoseOfOrientation(q.x, q.y, q.z, q.w);
        out.pan = p.pan;
        out.tilt = p.tilt;
      }
      head_.Store(out);
      auto end = Xr<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
      end.displayTime = frame.predictedDisplayTime;
      end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
      xrEndFrame(session_, &end);
    }
    if (running) xrEndSession(session_);
  }

  XrInstance instance_;
  XrSession session_;
  XrSpace view_;
  XrSpace local_;
  Seqlock<TrackedHead> head_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  // The session thread's.
  HeadPose held_;
  bool seen_tracked_ = false;
  bool lost_ = false;
};

}  // namespace

std::unique_ptr<HeadSource> OpenOpenXrHead(std::string& why_not) {
  // The loader prints its search to stderr; the run says what it found in one line.
  setenv("XR_LOADER_DEBUG", "none", 0);
  uint32_t count = 0;
  XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr);
  if (XR_FAILED(r)) {
    why_not = "no OpenXR runtime (" + ResultText(r) + ")";
    return nullptr;
  }
  std::vector<XrExtensionProperties> extensions(
      count, Xr<XrExtensionProperties>(XR_TYPE_EXTENSION_PROPERTIES));
  xrEnumerateInstanceExtensionProperties(nullptr, count, &count, extensions.data());
  bool headless = false;
  for (const auto& e : extensions)
    headless = headless || std::strcmp(e.extensionName, XR_MND_HEADLESS_EXTENSION_NAME) == 0;
  if (!headless) {
    // Without it a session needs a graphics binding, and frames submitted
    // from the view's GL context: not built yet.
    why_not = "the OpenXR runtime offers no " + std::string(XR_MND_HEADLESS_EXTENSION_NAME) +
              " (a head pose without rendering to the display)";
    return nullptr;
  }
  const char* enabled[] = {XR_MND_HEADLESS_EXTENSION_NAME};
  auto create = Xr<XrInstanceCreateInfo>(XR_TYPE_INSTANCE_CREATE_INFO);
  std::strncpy(create.applicationInfo.applicationName, "haptel", XR_MAX_APPLICATION_NAME_SIZE - 1);
  create.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  create.enabledExtensionCount = 1;
  create.enabledExtensionNames = enabled;
  XrInstance instance = XR_NULL_HANDLE;
  if (r = xrCreateInstance(&create, &instance); XR_FAILED(r)) {
    why_not = "no OpenXR runtime (xrCreateInstance: " + ResultText(r) + ")";
    return nullptr;
  }
  const auto fail = [&](const char* what, XrResult result, XrSession session = XR_NULL_HANDLE) {
    why_not = std::string("OpenXR ") + what + ": " + ResultText(result);
    if (session != XR_NULL_HANDLE) xrDestroySession(session);
    xrDestroyInstance(instance);
    return nullptr;
  };
  auto system_info = Xr<XrSystemGetInfo>(XR_TYPE_SYSTEM_GET_INFO);
  system_info.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  if (r = xrGetSystem(instance, &system_info, &system); XR_FAILED(r)) return fail("xrGetSystem", r);
  auto session_info = Xr<XrSessionCreateInfo>(XR_TYPE_SESSION_CREATE_INFO);
  session_info.systemId = system;  // headless: no graphics binding
  XrSession session = XR_NULL_HANDLE;
  if (r = xrCreateSession(instance, &session_info, &session); XR_FAILED(r))
    return fail("xrCreateSession", r);
  auto space = Xr<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
  space.poseInReferenceSpace.orientation.w = 1.0f;
  space.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  XrSpace view = XR_NULL_HANDLE;
  if (r = xrCreateReferenceSpace(session, &space, &view); XR_FAILED(r))
    return fail("the view space", r, session);
  space.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
  XrSpace local = XR_NULL_HANDLE;
  if (r = xrCreateReferenceSpace(session, &space, &local); XR_FAILED(r)) {
    xrDestroySpace(view);
    return fail("the local space", r, session);
  }
  return std::make_unique<OpenXrHead>(instance, session, view, local);
}

}  // namespace haptel::view
