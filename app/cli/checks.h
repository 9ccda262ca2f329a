#pragma once

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <string>

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

}  // namespace lumistage
