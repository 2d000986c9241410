// What a run ran on, for reports and benchmark tables: the CPU model and logical cores
// from /proc/cpuinfo (hardware_concurrency where that file is missing).
#pragma once

#include <fstream>
#include <string>
#include <thread>

namespace hsi {

struct Machine {
  std::string cpu = "unknown CPU";
  int cores = 0;
};

inline Machine this_machine() {
  Machine m;
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  bool named = false;
  while (std::getline(in, line)) {
    if (!named && line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      const size_t start = colon == std::string::npos ? std::string::npos : line.find_first_not_of(" \t", colon + 1);
      if (start != std::string::npos) {
        m.cpu = line.substr(start);
        named = true;
      }
    }
    if (line.rfind("processor", 0) == 0) ++m.cores;
  }
  if (m.cores == 0) m.cores = static_cast<int>(std::thread::hardware_concurrency());
  return m;
}

}  // namespace hsi
