// The files one hsi compare run writes into its folder, removed again if the run fails,
// so that nothing is left that looks like a finished report (report.md is written last).
#pragma once

#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "hsi/domain.h"

namespace hsi::compare {

class Outputs {
 public:
  explicit Outputs(std::filesystem::path dir) : dir_(std::move(dir)) {}
  Outputs(const Outputs&) = delete;
  Outputs& operator=(const Outputs&) = delete;
  ~Outputs() {
    if (committed_) return;
    for (const auto& p : written_) {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
    if (created_) {
      std::error_code ec;
      std::filesystem::remove(dir_, ec);  // only if empty
    }
  }
  // Creates the folder; removes an earlier run's report (which must not pass for this
  // one's if this one fails) and Fig. 8 plot (which must not stay next to a report of a
  // shape with holes).
  void open() {
    if (std::filesystem::exists(dir_) && !std::filesystem::is_directory(dir_))
      throw InputError("-o " + dir_.string() + ": exists and is not a folder");
    created_ = std::filesystem::create_directories(dir_);
    for (const char* stale : {"report.md", "report.json", "ccw16_distance.png"}) std::filesystem::remove(dir_ / stale);
  }
  // The path for a file about to be written, removed again unless commit() is reached.
  std::filesystem::path add(const std::string& name) {
    written_.push_back(dir_ / name);
    return dir_ / name;
  }
  void commit() { committed_ = true; }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::vector<std::filesystem::path> written_;
  bool created_ = false, committed_ = false;
};

}  // namespace hsi::compare
