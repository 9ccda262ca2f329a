#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace lumistage {

// What `lumistage eval` reports (docs/eval-report.md): sections of named figures in the order they
// were added (mocap, refinement, rendering... each stage adds its own), and a per-frame table
// whose columns the stages add the same way. Keys are unique across the whole report (JSON is
// flat: one object, every section's keys at the top, then "per_frame"); a key set twice keeps its
// place and takes the new value. Numbers that are not finite are written as null.
class EvalReport {
 public:
  struct Entry {
    std::string key;
    double number = 0;
    std::string text;  // a text value when is_text
    bool is_text = false;
  };
  struct Section {
    std::string name;
    std::vector<Entry> entries;
  };

  // Adds to (or creates, at the end) section `section`.
  void set(std::string_view section, std::string_view key, double value);
  void setText(std::string_view section, std::string_view key, std::string_view value);
  // A cell of the per-frame table: row `frame` (a session frame index; rows are kept sorted by
  // frame), column `column` (added on first use). Missing cells are null.
  void setFrame(int64_t frame, std::string_view column, double value);

  const std::vector<Section>& sections() const { return sections_; }
  const Entry* find(std::string_view key) const;
  const std::vector<std::string>& frameColumns() const { return columns_; }
  size_t frameRows() const { return frames_.size(); }

  // {"key": value, ..., "per_frame": [{"frame": 0, "column": value, ...}, ...]}
  std::string toJson() const;
  // Human-readable: one block per section, figures aligned; per-frame rows left out.
  std::string toText() const;

 private:
  Entry& entry(std::string_view section, std::string_view key);
  std::vector<Section> sections_;
  std::vector<std::string> columns_;
  std::vector<int64_t> frames_;
  std::vector<std::vector<double>> cells_;  // [row][column], NaN where missing
};

}  // namespace lumistage
