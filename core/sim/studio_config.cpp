#include "core/sim/studio_config.h"

#include <fmt/format.h>

#include <cmath>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/yaml_reader.h"
#include "core/body/motion_library.h"
#include "core/geometry/rig_file.h"

namespace lumistage {

StudioConfig loadStudioConfig(const std::filesystem::path& path) {
  const YamlReader in(path.string());
  const YAML::Node root = in.parseDocument(readFile(path));
  in.requireMap(root, "");
  in.checkKeys(root, "", {"format", "version", "rig", "actor", "motion", "look", "seed", "refine"});
  const YAML::Node format = in.required(root, "", "format", "'lumistage-studio'");
  if (in.string(format, "format") != "lumistage-studio") {
    in.fail(format, "format", "expected 'lumistage-studio': not a Lumistage studio config");
  }
  if (in.integer(in.required(root, "", "version", "1"), "version") != 1) {
    in.fail(root["version"], "version", "this Lumistage reads studio configs of version 1");
  }
  StudioConfig config;
  const YAML::Node rig =
      in.required(root, "", "rig", "the rig file's path (relative to this file)");
  config.rig_file = path.parent_path() / in.string(rig, "rig");
  config.rig = loadRig(config.rig_file);

  if (const YAML::Node actor = root["actor"]) {
    in.requireMap(actor, "actor");
    in.checkKeys(actor, "actor",
                 {"height_m", "arm_length_scale", "leg_length_scale", "shoulder_width_scale",
                  "hip_width_scale", "girth_scale", "belly_scale", "clothing", "vertices"});
    BodyShape& shape = config.actor.shape;
    auto positive = [&](const char* key, double& value) {
      if (!actor[key]) return;
      value = in.number(actor[key], YamlReader::child("actor", key));
      if (!(value > 0))
        in.fail(actor[key], YamlReader::child("actor", key), "expected a positive number");
    };
    positive("height_m", shape.height_m);
    positive("arm_length_scale", shape.arm_length_scale);
    positive("leg_length_scale", shape.leg_length_scale);
    positive("shoulder_width_scale", shape.shoulder_width_scale);
    positive("hip_width_scale", shape.hip_width_scale);
    positive("girth_scale", shape.girth_scale);
    positive("belly_scale", shape.belly_scale);
    if (actor["clothing"]) config.actor.clothing = in.boolean(actor["clothing"], "actor.clothing");
    if (actor["vertices"]) {
      config.actor.target_vertices = in.integer(actor["vertices"], "actor.vertices");
      if (config.actor.target_vertices < 200 || config.actor.target_vertices > 200000) {
        in.fail(actor["vertices"], "actor.vertices", "expected between 200 and 200000");
      }
    }
  }
  if (const YAML::Node motion = root["motion"]) {
    in.requireMap(motion, "motion");
    in.checkKeys(motion, "motion",
                 {"clip", "bvh", "fps", "start_s", "centre", "heading_deg", "offset_m"});
    if (motion["clip"]) {
      config.clip = in.string(motion["clip"], "motion.clip");
      bool known = false;
      std::string names;
      for (const std::string& name : builtinClipNames()) {
        known = known || name == config.clip;
        names += (names.empty() ? "" : ", ") + name;
      }
      if (!known)
        in.fail(motion["clip"], "motion.clip",
                "unknown clip '" + config.clip + "'; expected one of: " + names);
    }
    if (motion["bvh"])
      config.bvh_file = path.parent_path() / in.string(motion["bvh"], "motion.bvh");
    if (motion["fps"]) {
      config.fps = in.number(motion["fps"], "motion.fps");
      if (!(config.fps > 0 && config.fps <= 240))
        in.fail(motion["fps"], "motion.fps", "expected frames per second in (0, 240]");
    }
    MotionPlacement& placement = config.placement;
    if (motion["start_s"]) {
      placement.start_s = in.number(motion["start_s"], "motion.start_s");
      if (!(placement.start_s >= 0 && placement.start_s <= 3600))
        in.fail(motion["start_s"], "motion.start_s", "expected seconds in [0, 3600]");
    }
    if (motion["centre"]) placement.centre = in.boolean(motion["centre"], "motion.centre");
    if (motion["heading_deg"])
      placement.heading_deg = in.number(motion["heading_deg"], "motion.heading_deg");
    if (const YAML::Node offset = motion["offset_m"]) {
      in.requireSequence(offset, "motion.offset_m", 2);
      for (int i = 0; i < 2; ++i) {
        placement.offset_m[i] = in.number(offset[i], YamlReader::item("motion.offset_m", i));
        if (std::abs(placement.offset_m[i]) > 10)
          in.fail(offset[i], YamlReader::item("motion.offset_m", i),
                  "expected metres in [-10, 10]");
      }
    }
  }
  if (const YAML::Node look = root["look"]) {
    in.requireMap(look, "look");
    in.checkKeys(
        look, "look",
        {"backdrop", "screen_green", "unevenness", "spill", "noise_sigma", "pixel_format"});
    if (look["backdrop"]) {
      const std::string b = in.string(look["backdrop"], "look.backdrop");
      if (b == "green_screen") {
        config.look.backdrop = StudioLook::Backdrop::kGreenScreen;
      } else if (b == "room") {
        config.look.backdrop = StudioLook::Backdrop::kRoom;
      } else {
        in.fail(look["backdrop"], "look.backdrop",
                "expected green_screen or room, got '" + b + "'");
      }
    }
    if (const YAML::Node g = look["screen_green"]) {
      in.requireSequence(g, "look.screen_green", 3);
      for (int i = 0; i < 3; ++i) {
        config.look.screen_green[i] =
            float(in.number(g[i], YamlReader::item("look.screen_green", i)));
      }
    }
    if (look["unevenness"])
      config.look.unevenness = float(in.number(look["unevenness"], "look.unevenness"));
    if (look["spill"]) config.look.spill = float(in.number(look["spill"], "look.spill"));
    if (look["noise_sigma"])
      config.look.noise_sigma = float(in.number(look["noise_sigma"], "look.noise_sigma") / 255.0);
    if (look["pixel_format"]) {
      const std::string f = in.string(look["pixel_format"], "look.pixel_format");
      const std::optional<PixelFormat> format = parsePixelFormat(f);
      if (!format) {
        in.fail(look["pixel_format"], "look.pixel_format",
                "expected one of " + pixelFormatNames() + ", got '" + f + "'");
      }
      config.pixel_format = *format;
    }
  }
  if (const YAML::Node refine = root["refine"])
    config.refine = readRefineConfig(in, refine, "refine");
  if (root["seed"]) config.seed = static_cast<uint32_t>(in.integer(root["seed"], "seed"));
  return config;
}

std::string formatStudioConfig(const StudioConfig& config, const std::string& rig_file) {
  const BodyShape& shape = config.actor.shape;
  const MotionPlacement& placement = config.placement;
  const StudioLook& look = config.look;
  std::string out =
      "# A Lumistage virtual studio: see docs/virtual-studio.md.\n"
      "format: lumistage-studio\n"
      "version: 1\n";
  out += fmt::format("rig: {}\n", rig_file);
  out += fmt::format(
      "actor:\n  height_m: {}\n  arm_length_scale: {}\n  leg_length_scale: {}\n"
      "  shoulder_width_scale: {}\n  hip_width_scale: {}\n  girth_scale: {}\n"
      "  belly_scale: {}\n  clothing: {}\n  vertices: {}\n",
      shape.height_m, shape.arm_length_scale, shape.leg_length_scale, shape.shoulder_width_scale,
      shape.hip_width_scale, shape.girth_scale, shape.belly_scale, config.actor.clothing,
      config.actor.target_vertices);
  out += "motion:\n";
  if (config.bvh_file.empty())
    out += fmt::format("  clip: {}\n", config.clip);
  else
    out += fmt::format("  bvh: '{}'\n", std::filesystem::absolute(config.bvh_file).string());
  out += fmt::format(
      "  fps: {}\n  start_s: {}\n  centre: {}\n  heading_deg: {}\n  offset_m: [{}, {}]\n",
      config.fps, placement.start_s, placement.centre, placement.heading_deg,
      placement.offset_m.x(), placement.offset_m.y());
  out += fmt::format(
      "look:\n  backdrop: {}\n  screen_green: [{}, {}, {}]\n  unevenness: {}\n  spill: {}\n"
      "  noise_sigma: {}\n  pixel_format: {}\n",
      look.backdrop == StudioLook::Backdrop::kRoom ? "room" : "green_screen", look.screen_green.x(),
      look.screen_green.y(), look.screen_green.z(), look.unevenness, look.spill,
      look.noise_sigma * 255.0, pixelFormatName(config.pixel_format));
  out += fmt::format("seed: {}\n", config.seed);
  return out;
}

}  // namespace lumistage
