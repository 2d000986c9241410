// Shared by the benchmarks' command lines (CLI11).
#pragma once

#include <CLI/CLI.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace hsi::bench {

// "1,4,16": worker (thread) counts, each at least 1; CLI::ValidationError naming `option`.
inline std::vector<int> parse_counts(const std::string& s, const std::string& option) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) {
      int w = 0;
      size_t used = 0;
      try {
        w = std::stoi(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != item.size()) throw CLI::ValidationError(option, "not a count: '" + item + "'");
      if (w < 1) throw CLI::ValidationError(option, "counts must be at least 1 (got " + item + ")");
      out.push_back(w);
    }
  if (out.empty()) throw CLI::ValidationError(option, "no count given");
  return out;
}

}  // namespace hsi::bench
