# Shared by scripts/run and scripts/test: install what is missing (apt), then
# configure and build into build/ (Release). Idempotent; fast when up to date.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${HAPTEL_BUILD_DIR:-$ROOT/build}"

# Debian 12 packages Haptel builds and runs with (scripts/run installs these).
HAPTEL_PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libbullet-dev
  libfastrtps-dev libfastcdr-dev fastddsgen
  libopencv-dev libyaml-cpp-dev libsqlite3-dev sqlite3
  libtinyxml2-dev   # the MHaptic XML scene files (also a Fast DDS dependency)
  libsdl2-dev
  libopenxr-dev libopenxr-loader1   # a head-mounted display's head pose (haptel run --head openxr)
  libavformat-dev libavcodec-dev libavutil-dev   # the --record MP4 (H.264 through libx264), each write checked
  openssl libssl-dev   # DDS Security: `haptel security init` and the certificates' check at start
  libcpp-httplib-dev   # the study's experimenter's console (a web page on 127.0.0.1)
  libzstd-dev liblz4-dev   # the session file's chunks (MCAP: zstd or LZ4 frames)
  # The operator's view: OpenGL 3.3 core through Mesa (llvmpipe without a GPU).
  libgl-dev libegl-dev libgl1-mesa-dri libegl-mesa0
)

# What only the test suite needs (scripts/test adds these; a fresh
# `scripts/run` does not wait for them).
HAPTEL_TEST_PACKAGES=(
  catch2
  cyclonedds-dev cyclonedds-tools   # the ROS 2 adapter's test: an independent DDS (Cyclone) stands in for a ROS 2 robot
  iproute2   # the link test's second host: another network namespace joined by a veth pair
  chromium chromium-driver python3-selenium   # the study console tested in a real browser
  python3-can can-utils   # the CAN logs checked with python-can's LogReader and log2asc
  xvfb xauth xdotool   # an X server of its own for the window tests, xdotool for keys
  libxtst-dev   # the pointer pilot (testing/): the real X pointer, button and keys through XTest
  clang-format   # the suite's check that every C++ file is as .clang-format says (scripts/format)
)

# Node.js for the session files' reference reader (tests only). Debian's
# nodejs and npm; a machine whose Node.js comes from elsewhere (NodeSource's
# nodejs carries its own npm and conflicts with Debian's) keeps its own.
HAPTEL_TEST_NODE_PACKAGES=(nodejs npm)
# What npm installs into build/node-tools/ (pinned; cached there, installed
# again only when this list changes): the TypeScript reference reader of
# MCAP (@mcap/core, with @mcap/support's zstd and LZ4), and the OMG IDL
# parser and CDR decoder the session tests decode every message with.
HAPTEL_TEST_NODE_MODULES=(
  @mcap/core@2.2.2 @mcap/support@1.1.0
  @foxglove/omgidl-parser@1.1.0 @foxglove/omgidl-serialization@1.0.3
)

haptel_log() { echo "[haptel] $*" >&2; }

# haptel_install_node_tools: node and npm (Debian's, when there are none),
# then HAPTEL_TEST_NODE_MODULES into $BUILD_DIR/node-tools/ unless that
# exact list is there already (tests/mcap/mcap_reference_reader.mjs loads
# them from there).
haptel_install_node_tools() {
  command -v npm >/dev/null 2>&1 || haptel_install_deps "${HAPTEL_TEST_NODE_PACKAGES[@]}"
  local dir="$BUILD_DIR/node-tools" wanted="${HAPTEL_TEST_NODE_MODULES[*]}"
  if [ -f "$dir/.installed" ] && [ "$(cat "$dir/.installed")" = "$wanted" ]; then
    return 0
  fi
  haptel_log "installing the MCAP reference reader (npm) into $dir"
  mkdir -p "$dir"
  npm install --prefix "$dir" --no-audit --no-fund --silent "${HAPTEL_TEST_NODE_MODULES[@]}" >&2
  echo "$wanted" >"$dir/.installed"
}

# haptel_install_deps [PACKAGE...]: installs what is missing of the given
# packages (default: what running needs).
haptel_install_deps() {
  local wanted=("$@")
  [ ${#wanted[@]} -eq 0 ] && wanted=("${HAPTEL_PACKAGES[@]}")
  local missing=()
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  haptel_log "installing missing packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# haptel_build tests|product: configures build/ (Release) and builds. With
# `tests`, everything (the suite included); with `product`, the programs
# alone (haptel, which depends on haptel-vehicle, haptel-device-server and
# haptel-bench), configured without the tests when build/ is new.
haptel_build() {
  local what="${1:-tests}" testing=OFF target=(--target haptel)
  [ "$what" = "tests" ] && { testing=ON; target=(); }
  if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
    haptel_log "configuring $BUILD_DIR"
    cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=$testing >/dev/null
  elif [ "$testing" = ON ] && grep -q '^BUILD_TESTING:BOOL=OFF' "$BUILD_DIR/CMakeCache.txt"; then
    haptel_log "configuring $BUILD_DIR with the tests"
    cmake -S "$ROOT" -B "$BUILD_DIR" -DBUILD_TESTING=ON >/dev/null
  fi
  haptel_log "building $what (log: $BUILD_DIR/build.log)"
  if ! cmake --build "$BUILD_DIR" -j"$(nproc)" "${target[@]}" >"$BUILD_DIR/build.log" 2>&1; then
    grep -vE '^\[ *[0-9]+%\]' "$BUILD_DIR/build.log" | tail -n 80 >&2
    haptel_log "build failed"
    return 1
  fi
}

# haptel_link_programs: makes `haptel` and `haptel-vehicle` callable by name,
# as the README and docs/ write them: symlinks to build/bin/ in a directory
# on the PATH. A link, not a copy, so each build is what runs, and the
# programs still find their siblings (haptel-vehicle, haptel-bench) beside
# their real selves. Root (the target Debian machine): /usr/local/bin, on
# every user's PATH and sudo's; anyone else: ~/.local/bin (Debian's
# ~/.profile puts it on the PATH once it exists; until the next login the
# script prints the one line to type). HAPTEL_BIN_LINKS=DIR picks another
# directory, HAPTEL_BIN_LINKS=none makes none.
haptel_link_programs() {
  local dir="${HAPTEL_BIN_LINKS:-}"
  [ "$dir" = "none" ] && return 0
  if [ -z "$dir" ]; then
    if [ "$(id -u)" -eq 0 ]; then dir=/usr/local/bin; else dir="$HOME/.local/bin"; fi
  fi
  mkdir -p "$dir"
  local program
  for program in haptel haptel-vehicle; do
    ln -sfn "$BUILD_DIR/bin/$program" "$dir/$program"
  done
  case ":$PATH:" in
    *":$dir:"*) haptel_log "haptel and haptel-vehicle are on the PATH ($dir -> $BUILD_DIR/bin)" ;;
    *) haptel_log "haptel and haptel-vehicle linked in $dir, which is not on this shell's PATH; type: export PATH=\"$dir:\$PATH\"" ;;
  esac
}

# scripts/test --tsan: the tests whose code runs on several threads at once,
# built with ThreadSanitizer into build-tsan/ (only these targets) and run
# with halt_on_error: the first race fails its test.
# - test_core (seqlock, periodic thread, histogram), test_haptics (HAL and
#   servo loop), test_udp (UDP device and server), test_physics (physics
#   thread and controls link), test_view_input (SDL input pump);
# - test_link: DDS participants, writers and readers' callbacks;
# - test_video_stream: the video receiver's threads against a DDS vehicle
#   stand-in (H.264), and the camera streamer's;
# - test_mediator: the session's parts;
# - test_session_threads: a real-time run and a two-robot fleet (its
#   handovers) attached to vehicle nodes in the same process: the session
#   loop, servo, physics, DDS callbacks and the vehicles' loops together;
# - test_third_person_view [threads]: its picture hand-over to the view;
# - test_study_console: the console's HTTP workers and SQLite.
# Fast DDS's timed mutexes need tests/support/tsan_clocklock.cpp (linked
# into every test of this build). scripts/tsan.supp lists what is left out
# or suppressed, each with its reason.
HAPTEL_TSAN_TESTS=(test_core test_haptics test_udp test_physics test_view_input test_link
                   test_video_stream test_mediator test_session_threads test_third_person_view test_study_console)

haptel_test_tsan() {
  local dir="${HAPTEL_TSAN_BUILD_DIR:-$ROOT/build-tsan}"
  if [ ! -f "$dir/CMakeCache.txt" ]; then
    haptel_log "configuring $dir (ThreadSanitizer)"
    cmake -S "$ROOT" -B "$dir" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON -DHAPTEL_SANITIZE=thread >/dev/null
  else
    # Configured again: a test target added since (by name below) is
    # unknown to the old Makefiles until CMake has run.
    cmake "$dir" >/dev/null
  fi
  haptel_log "building ${HAPTEL_TSAN_TESTS[*]} with ThreadSanitizer (log: $dir/build.log)"
  if ! cmake --build "$dir" -j"$(nproc)" --target "${HAPTEL_TSAN_TESTS[@]}" >"$dir/build.log" 2>&1; then
    grep -vE '^\[ *[0-9]+%\]' "$dir/build.log" | tail -n 80 >&2
    haptel_log "build failed"
    return 1
  fi
  local names
  names="$(IFS='|'; echo "${HAPTEL_TSAN_TESTS[*]}")"
  cd "$dir"
  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$ROOT/scripts/tsan.supp ${TSAN_OPTIONS:-}" \
    ctest --output-on-failure --timeout 900 -j"$(nproc)" -R "^($names)\$" "$@"
}
