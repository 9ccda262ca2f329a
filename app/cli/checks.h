#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

#include "core/body/human_model.h"

namespace lumistage {

// A number from `lo` to `hi` (both included), finite: CLI::Range lets NaN through (its comparisons
// are all false), and words its refusal with the type's full range ("0 to 1.797...e308").
inline CLI::Validator within(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double value = 0;
        try {
          size_t used = 0;
          value = std::stod(text, &used);
          if (used != text.size()) return "expected a number, got '" + text + "'";
        } catch (const std::exception&) {
          return "expected a number, got '" + text + "'";
        }
        if (!std::isfinite(value) || value < lo || value > hi)
          return fmt::format("expected a number from {} to {}, got {}", lo, hi, text);
        return {};
      },
      fmt::format("[{} - {}]", lo, hi));
}

// --body standard|fine: which generic human the studio and its nodes pose and refine; every
// process of a stage must be given the same.
inline CLI::Option* addBodyOption(CLI::App& app, BodyDetail& body) {
  return app
      .add_option_function<std::string>(
          "--body", [&body](const std::string& name) { body = parseBodyDetail(name); },
          "the generic human posed and refined: standard (about 2000 vertices: four nodes and the "
          "studio on one PC) or fine (about 4000: nodes on PCs of their own; sharper views, twice "
          "the nodes' work); the studio and every node alike")
      ->check(
          CLI::IsMember({bodyDetailName(BodyDetail::kStandard), bodyDetailName(BodyDetail::kFine)}))
      ->default_str(bodyDetailName(body));
}

}  // namespace lumistage
