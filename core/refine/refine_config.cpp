#include "core/refine/refine_config.h"

#include <yaml-cpp/yaml.h>

#include "core/base/yaml_reader.h"

namespace lumistage {

RefineConfig readRefineConfig(const YamlReader& in, const YAML::Node& node, std::string_view key) {
  RefineConfig config;
  in.requireMap(node, key);
  in.checkKeys(node, key,
               {"offset_count",
                "t_max_m",
                "t_inward_m",
                "outside_weight",
                "outward_weight",
                "off_contour_outward_weight",
                "colour_weight",
                "colour_sigma",
                "unseen_colour",
                "smooth_weight",
                "smooth_reference_vertices",
                "temporal_weight",
                "tie_margin",
                "smooth_iterations",
                "depth_map_step",
                "depth_tolerance_m",
                "min_facing_cos",
                "colour_bits",
                "window_points",
                "window_m",
                "contour_weight",
                "contour_cos",
                "contour_probe_m",
                "colour_purity",
                "refined_depth_tolerance_m",
                "despill"});
  auto number = [&](const char* name, double& value, double lo, double hi, const char* expected) {
    if (!node[name]) return;
    const std::string path = YamlReader::child(key, name);
    value = in.number(node[name], path);
    if (!(value >= lo && value <= hi)) in.fail(node[name], path, expected);
  };
  auto integer = [&](const char* name, int& value, int lo, int hi, const char* expected) {
    if (!node[name]) return;
    const std::string path = YamlReader::child(key, name);
    value = in.integer(node[name], path);
    if (value < lo || value > hi) in.fail(node[name], path, expected);
  };
  static_assert(RefineConfig::kMaxOffsetCount == 32, "the message below says 32");
  integer("offset_count", config.offset_count, 1, RefineConfig::kMaxOffsetCount,
          "expected 1 to 32 offsets");
  number("t_max_m", config.t_max_m, 0.0, 0.5, "expected metres in [0, 0.5]");
  number("t_inward_m", config.t_inward_m, 0.0, 0.5, "expected metres in [0, 0.5]");
  number("outside_weight", config.outside_weight, 0, 1e6, "expected a weight >= 0");
  number("outward_weight", config.outward_weight, 0, 1e6, "expected a weight >= 0");
  number("off_contour_outward_weight", config.off_contour_outward_weight, 0, 1e6,
         "expected a weight >= 0");
  number("colour_weight", config.colour_weight, 0, 1e6, "expected a weight >= 0");
  number("colour_sigma", config.colour_sigma, 0.1, 255, "expected 8-bit levels in [0.1, 255]");
  number("unseen_colour", config.unseen_colour, 0, 1, "expected a value in [0, 1]");
  number("smooth_weight", config.smooth_weight, 0, 1e6, "expected a weight >= 0");
  integer("smooth_reference_vertices", config.smooth_reference_vertices, 0, 1 << 22,
          "expected a vertex count >= 0");
  number("temporal_weight", config.temporal_weight, 0, 1e6, "expected a weight >= 0");
  number("tie_margin", config.tie_margin, 0, 1e6, "expected a margin >= 0");
  integer("smooth_iterations", config.smooth_iterations, 0, 100, "expected 0 to 100");
  integer("depth_map_step", config.depth_map_step, 1, 64, "expected 1 to 64 pixels");
  number("depth_tolerance_m", config.depth_tolerance_m, 0, 1, "expected metres in [0, 1]");
  number("refined_depth_tolerance_m", config.refined_depth_tolerance_m, 0, 1,
         "expected metres in [0, 1]");
  number("min_facing_cos", config.min_facing_cos, -1, 1, "expected a cosine in [-1, 1]");
  integer("colour_bits", config.colour_bits, 1, 8, "expected 1 to 8 bits");
  integer("window_points", config.window_points, 1, 3, "expected 1 or 3 points");
  if (config.window_points == 2)
    in.fail(node["window_points"], YamlReader::child(key, "window_points"),
            "expected 1 or 3 points");
  number("window_m", config.window_m, 0, 0.05, "expected metres in [0, 0.05]");
  number("contour_weight", config.contour_weight, 0, 1e6, "expected a weight >= 0");
  number("contour_cos", config.contour_cos, 0, 1, "expected a cosine in [0, 1]");
  number("contour_probe_m", config.contour_probe_m, 0, 0.5, "expected metres in [0, 0.5]");
  number("colour_purity", config.colour_purity, 0.01, 1, "expected a share in [0.01, 1]");
  if (node["despill"])
    config.despill = in.boolean(node["despill"], YamlReader::child(key, "despill"));
  return config;
}

}  // namespace lumistage
