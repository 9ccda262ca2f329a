#!/usr/bin/env bash
# Installs the Debian packages Lumistage needs to build, test and run, and only those that are
# missing: a second run does nothing and takes well under a second.
# Usage: packaging/install-deps.sh [--check]   (--check lists what is missing and exits 1 if any)
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config clang-format
  # clang with libFuzzer for the message decoder fuzz test (tests/fuzz)
  clang libclang-rt-14-dev
  # GUI and GL: Qt6 widgets/OpenGL widgets/test, headless EGL through Mesa, GLFW + Dear ImGui
  qt6-base-dev qt6-base-dev-tools libqt6opengl6-dev libgl-dev libopengl-dev libegl-dev libgles-dev
  libegl-mesa0 libgl1-mesa-dri mesa-utils libglfw3-dev libimgui-dev xvfb xauth
  # packaging: man pages from --help, desktop entry check, file (CPack's Debian generator reads
  # the binaries' library dependencies with it; not in a minimal Debian)
  help2man desktop-file-utils file
  # vision, maths, geometry
  libopencv-dev libeigen3-dev libceres-dev libassimp-dev
  # cameras: Aravis (GigE Vision / USB3 Vision) and its tools (fake GigE camera)
  libaravis-dev aravis-tools libusb-1.0-0-dev
  # private network namespaces (ip, unshare) for one loopback address per virtual GigE camera
  iproute2 util-linux
  # transport and messages
  libzmq3-dev cppzmq-dev libflatbuffers-dev flatbuffers-compiler
  # video files: MP4/H.264 (libx264 through libavcodec) and Motion-JPEG AVI
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  # compression of the nodes' refinement statistics
  libzstd-dev
  # OSC for the skeleton's live feed (VMC protocol); the packages' runtime liblo7 comes from
  # dpkg-shlibdeps
  liblo-dev
  # logging, command line, config
  libspdlog-dev libfmt-dev libcli11-dev libyaml-cpp-dev libtoml11-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  exit 0
fi
if [[ "${1:-}" == "--check" ]]; then
  printf 'missing: %s\n' "${missing[*]}"
  exit 1
fi

echo "lumistage: installing ${#missing[@]} Debian package(s): ${missing[*]}"
sudo=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "lumistage: need root or sudo to install packages" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
# The package lists of a fresh machine are empty or stale: refresh them once before installing.
"${sudo[@]}" apt-get update -q
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
