#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

#include "core/base/error.h"
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

// --body standard|fine|FILE: which human the studio and its nodes pose and refine; every process
// of a stage must be given the same.
inline CLI::Option* addBodyOption(CLI::App& app, BodyChoice& body) {
  return app
      .add_option_function<std::string>(
          "--body", [&body](const std::string& name) { body = parseBodyChoice(name); },
          "the human posed and refined: standard (the generic human, about 2000 vertices: four "
          "nodes and the studio on one PC), fine (about 4000: nodes on PCs of their own; sharper "
          "views, twice the nodes' work) or the actor's own rigged human from a file (glTF/GLB, "
          "FBX, DAE, X; see docs/bodies.md); the studio and every node alike")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              parseBodyChoice(text);
              return {};
            } catch (const Error& e) {
              return e.what();
            }
          },
          "standard|fine|FILE"))
      ->default_str(bodyChoiceName(body));
}

}  // namespace lumistage
