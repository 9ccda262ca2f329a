#include "core/eval/eval_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lumistage {

namespace {

std::string jsonString(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", int(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  if (v == std::floor(v) && std::abs(v) < 1e15) return fmt::format("{}", int64_t(v));
  return fmt::format("{:.6g}", v);
}

}  // namespace

EvalReport::Entry& EvalReport::entry(std::string_view section, std::string_view key) {
  for (Section& s : sections_) {
    for (Entry& e : s.entries) {
      if (e.key == key) return e;
    }
  }
  auto it = std::find_if(sections_.begin(), sections_.end(),
                         [&](const Section& s) { return s.name == section; });
  if (it == sections_.end()) {
    sections_.push_back({std::string(section), {}});
    it = sections_.end() - 1;
  }
  it->entries.push_back({std::string(key), 0, {}, false});
  return it->entries.back();
}

void EvalReport::set(std::string_view section, std::string_view key, double value) {
  Entry& e = entry(section, key);
  e.number = value;
  e.is_text = false;
}

void EvalReport::setText(std::string_view section, std::string_view key, std::string_view value) {
  Entry& e = entry(section, key);
  e.text = value;
  e.is_text = true;
}

void EvalReport::setFrame(int64_t frame, std::string_view column, double value) {
  auto col = std::find(columns_.begin(), columns_.end(), column);
  if (col == columns_.end()) {
    columns_.emplace_back(column);
    col = columns_.end() - 1;
    for (auto& row : cells_) row.push_back(std::numeric_limits<double>::quiet_NaN());
  }
  const auto at = std::lower_bound(frames_.begin(), frames_.end(), frame);
  const size_t row = size_t(at - frames_.begin());
  if (at == frames_.end() || *at != frame) {
    frames_.insert(at, frame);
    cells_.insert(cells_.begin() + row,
                  std::vector<double>(columns_.size(), std::numeric_limits<double>::quiet_NaN()));
  }
  cells_[row][size_t(col - columns_.begin())] = value;
}

const EvalReport::Entry* EvalReport::find(std::string_view key) const {
  for (const Section& s : sections_) {
    for (const Entry& e : s.entries) {
      if (e.key == key) return &e;
    }
  }
  return nullptr;
}

std::string EvalReport::toJson() const {
  std::string out = "{";
  bool first = true;
  for (const Section& s : sections_) {
    for (const Entry& e : s.entries) {
      out += fmt::format("{}\n  {}: {}", first ? "" : ",", jsonString(e.key),
                         e.is_text ? jsonString(e.text) : jsonNumber(e.number));
      first = false;
    }
  }
  out += fmt::format("{}\n  \"per_frame\": [", first ? "" : ",");
  for (size_t r = 0; r < frames_.size(); ++r) {
    out += fmt::format("{}\n    {{\"frame\": {}", r ? "," : "", frames_[r]);
    for (size_t c = 0; c < columns_.size(); ++c)
      out += fmt::format(", {}: {}", jsonString(columns_[c]), jsonNumber(cells_[r][c]));
    out += "}";
  }
  out += frames_.empty() ? "]\n}\n" : "\n  ]\n}\n";
  return out;
}

std::string EvalReport::toText() const {
  std::string out;
  for (const Section& s : sections_) {
    out += s.name + "\n";
    size_t width = 0;
    for (const Entry& e : s.entries) width = std::max(width, e.key.size());
    for (const Entry& e : s.entries) {
      out += fmt::format("  {:<{}}  {}\n", e.key, width,
                         e.is_text ? e.text : fmt::format("{:.4g}", e.number));
    }
  }
  return out;
}

}  // namespace lumistage
