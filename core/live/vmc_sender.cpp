#include "core/live/vmc_sender.h"

#include <fmt/format.h>
#include <lo/lo.h>
#include <netdb.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <utility>

#include "core/base/error.h"
#include "core/net/posed_body.h"

namespace lumistage {

namespace {

// Our joint names (human_skeleton.h) and Unity's HumanBodyBones they are.
constexpr std::array<std::pair<const char*, const char*>, 22> kUnityBones{{
    {"pelvis", "Hips"},
    {"spine1", "Spine"},
    {"spine2", "Chest"},
    {"spine3", "UpperChest"},
    {"neck", "Neck"},
    {"head", "Head"},
    {"left_clavicle", "LeftShoulder"},
    {"left_shoulder", "LeftUpperArm"},
    {"left_elbow", "LeftLowerArm"},
    {"left_wrist", "LeftHand"},
    {"right_clavicle", "RightShoulder"},
    {"right_shoulder", "RightUpperArm"},
    {"right_elbow", "RightLowerArm"},
    {"right_wrist", "RightHand"},
    {"left_hip", "LeftUpperLeg"},
    {"left_knee", "LeftLowerLeg"},
    {"left_ankle", "LeftFoot"},
    {"left_foot", "LeftToes"},
    {"right_hip", "RightUpperLeg"},
    {"right_knee", "RightLowerLeg"},
    {"right_ankle", "RightFoot"},
    {"right_foot", "RightToes"},
}};

const char* unityBoneOf(const std::string& joint) {
  for (const auto& [ours, unity] : kUnityBones)
    if (joint == ours) return unity;
  return nullptr;
}

// Ours to Unity's: X = x, Y = z, Z = y.
Eigen::Matrix3d swapYZ() {
  Eigen::Matrix3d s;
  s << 1, 0, 0, 0, 0, 1, 0, 1, 0;
  return s;
}

constexpr auto kTellEvery = std::chrono::seconds(10);

}  // namespace

std::string OscTarget::text() const {
  return host.find(':') != std::string::npos ? fmt::format("[{}]:{}", host, port)
                                             : fmt::format("{}:{}", host, port);
}

OscTarget parseOscTarget(std::string_view text) {
  const auto bad = [&](std::string_view why) {
    return Error(fmt::format(
        "OSC target {}: {}; expected HOST:PORT, e.g. 127.0.0.1:{} (VMC's usual port) or "
        "[::1]:{}",
        quotedInput(text), why, VmcSender::kDefaultPort, VmcSender::kDefaultPort));
  };
  const size_t colon = text.rfind(':');
  if (colon == std::string_view::npos) throw bad("no port");
  std::string_view host = text.substr(0, colon), port = text.substr(colon + 1);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  } else if (host.find(':') != std::string_view::npos) {
    throw bad("an IPv6 address goes in brackets");
  }
  if (host.empty()) throw bad("no host");
  OscTarget target{std::string(host), 0};
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), target.port);
  if (port.empty() || error != std::errc() || end != port.data() + port.size() || target.port < 1 ||
      target.port > 65535)
    throw bad("the port must be a number from 1 to 65535");
  return target;
}

Eigen::Vector3d toUnityPosition(const Eigen::Vector3d& ours) {
  return {ours.x(), ours.z(), ours.y()};
}

Eigen::Quaterniond toUnityRotation(const Eigen::Matrix3d& ours) {
  static const Eigen::Matrix3d s = swapYZ();
  Eigen::Quaterniond q(Eigen::Matrix3d(s * ours * s));
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

// The bundle and its messages, made once: each frame writes its numbers into the messages' own
// arguments (lo_message_get_argv points into their data) and serialises the bundle again.
struct VmcSender::Osc {
  lo_bundle bundle = nullptr;
  lo_arg** root = nullptr;
  std::vector<lo_arg**> bones;
  lo_arg** ok = nullptr;
  lo_arg** time = nullptr;

  lo_arg** add(const char* path, lo_message message) {
    if (!message || lo_bundle_add_message(bundle, path, message) != 0) {
      if (message) lo_message_free(message);
      throw Error(fmt::format("VMC over OSC: liblo could not make the message {}", path));
    }
    return lo_message_get_argv(message);
  }
  static lo_message pose(const char* name) {
    lo_message m = lo_message_new();
    lo_message_add_string(m, name);
    for (int k = 0; k < 7; ++k) lo_message_add_float(m, k == 6 ? 1.0f : 0.0f);
    return m;
  }
  ~Osc() {
    if (bundle) lo_bundle_free_recursive(bundle);
  }
};

VmcSender::VmcSender(const OscTarget& target, const Skeleton& skeleton)
    : target_(target), skeleton_(skeleton), start_(std::chrono::steady_clock::now()) {
  // Our joints that are humanoid bones, parents first, each with its nearest ancestor that is one.
  std::vector<int> bone_of(skeleton_.jointCount(), -1);
  for (int j = 0; j < skeleton_.jointCount(); ++j) {
    const char* name = unityBoneOf(skeleton_.joint(j).name);
    if (!name) continue;
    int parent = skeleton_.joint(j).parent;
    while (parent >= 0 && bone_of[parent] < 0) parent = skeleton_.joint(parent).parent;
    bone_of[j] = int(bones_.size());
    bones_.push_back({name, j, parent >= 0 ? bone_of[parent] : -1});
  }
  if (!skeleton_.findJoint("pelvis"))
    throw Error("VMC over OSC: the body's skeleton has no joint named pelvis (Unity's Hips)");

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string port = std::to_string(target_.port);
  if (const int error = getaddrinfo(target_.host.c_str(), port.c_str(), &hints, &found)) {
    throw Error(fmt::format("OSC target {}: the host does not resolve ({})", target_.text(),
                            gai_strerror(error)));
  }
  socket_ = ::socket(found->ai_family, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  const int socket_error = errno;
  const auto* bytes = reinterpret_cast<const uint8_t*>(found->ai_addr);
  address_.assign(bytes, bytes + found->ai_addrlen);
  freeaddrinfo(found);
  if (socket_ < 0) {
    throw Error(fmt::format("OSC target {}: no UDP socket: {}", target_.text(),
                            std::strerror(socket_error)));
  }

  osc_ = std::make_unique<Osc>();
  osc_->bundle = lo_bundle_new(LO_TT_IMMEDIATE);
  if (!osc_->bundle) throw Error("VMC over OSC: liblo could not make a bundle");
  osc_->root = osc_->add("/VMC/Ext/Root/Pos", Osc::pose("root"));
  for (const VmcBone& bone : bones_)
    osc_->bones.push_back(osc_->add("/VMC/Ext/Bone/Pos", Osc::pose(bone.name)));
  lo_message ok = lo_message_new();
  for (int k = 0; k < 3; ++k) lo_message_add_int32(ok, k == 0 ? 1 : 0);
  osc_->ok = osc_->add("/VMC/Ext/OK", ok);
  lo_message time = lo_message_new();
  lo_message_add_float(time, 0.0f);
  osc_->time = osc_->add("/VMC/Ext/T", time);
  packet_.resize(lo_bundle_length(osc_->bundle));
}

VmcSender::~VmcSender() {
  if (socket_ >= 0) ::close(socket_);
}

void VmcSender::writeBones(const PoseData& pose) {
  poseFromMessage(pose, skeleton_.jointCount(), pose_);
  skeleton_.forwardKinematics(pose_, global_);
  const double scale = pose.scale;  // about the stage's origin, as the nodes pose the body
  for (VmcBone& bone : bones_) {
    const Eigen::Isometry3d& joint = global_[bone.joint];
    Eigen::Matrix3d rotation = joint.linear();
    Eigen::Vector3d position = scale * joint.translation();
    if (bone.parent >= 0) {  // relative to the parent bone; Hips: to the root, the origin
      const Eigen::Isometry3d& parent = global_[bones_[bone.parent].joint];
      rotation = parent.linear().transpose() * joint.linear();
      position = parent.linear().transpose() * (position - scale * parent.translation());
    }
    bone.position = toUnityPosition(position);
    bone.rotation = toUnityRotation(rotation);
  }
}

bool VmcSender::send(const PoseData& pose, bool tracked) {
  writeBones(pose);
  for (size_t b = 0; b < bones_.size(); ++b) {
    lo_arg** args = osc_->bones[b];
    const VmcBone& bone = bones_[b];
    for (int k = 0; k < 3; ++k) args[1 + k]->f = float(bone.position[k]);
    const Eigen::Vector4d q = bone.rotation.coeffs();  // x, y, z, w: VMC's order
    for (int k = 0; k < 4; ++k) args[4 + k]->f = float(q[k]);
  }
  osc_->ok[1]->i = tracked ? 3 : 0;  // calibrated, or uncalibrated
  const auto now = std::chrono::steady_clock::now();
  osc_->time[0]->f = std::chrono::duration<float>(now - start_).count();
  size_t size = packet_.size();
  lo_bundle_serialise(osc_->bundle, packet_.data(), &size);
  const ssize_t wrote =
      ::sendto(socket_, packet_.data(), size, MSG_DONTWAIT | MSG_NOSIGNAL,
               reinterpret_cast<const sockaddr*>(address_.data()), socklen_t(address_.size()));
  if (wrote == ssize_t(size)) {
    ++sent_;
    return true;
  }
  const int error = errno;
  ++lost_;
  ++lost_untold_;
  if (told_ == std::chrono::steady_clock::time_point{} || now - told_ >= kTellEvery) {
    spdlog::warn(
        "VMC over OSC to {}: a frame's bundle was not sent ({}); {} lost since the last "
        "word (said at most every {} s)",
        target_.text(), wrote < 0 ? std::strerror(error) : "sent in part", lost_untold_,
        kTellEvery.count());
    told_ = now;
    lost_untold_ = 0;
  }
  return false;
}

}  // namespace lumistage
