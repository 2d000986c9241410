// Random closed polylines for the crossing searches' tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "hsi/domain.h"

namespace hsi::test {

// Random closed polylines of one kind, before scaling: 0 noisy concentric circles
// (simple, apart), 1 random walks (many crossings), 2 walks on the integer grid
// (collinear overlaps, touchings at vertices, shared vertices, repeated points), 3 grid
// walks with steps of 1e-8 to 1e-11 of the size mixed in (around the merge tolerance
// of 1e-9), 4 integer polygons with spikes (a vertex, then back along the same line:
// fold-backs of neighbours, some exactly onto the previous vertex), 5 many small loops
// in a box (loop against loop; some collapse to fewer than 3 distinct points).
inline std::vector<Loop> random_loops(std::mt19937& rng, int kind, int points) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> step(-1, 1), coin(0, 9), grid(-6, 6);
  std::vector<Loop> loops;
  if (kind == 5) {
    for (int l = 0; l < std::max(2, points / 8); ++l) {
      Loop L;
      const cd c(grid(rng), grid(rng));
      const int n = 1 + coin(rng);
      for (int i = 0; i < n; ++i) L.push_back(coin(rng) < 2 ? c : c + cd(step(rng), step(rng)));
      loops.push_back(L);
    }
    return loops;
  }
  loops.resize(3);
  for (size_t l = 0; l < loops.size(); ++l) {
    Loop& L = loops[l];
    const int n = std::max(1, points / 3);
    cd z{0, 0};
    for (int i = 0; i < n; ++i) {
      if (kind == 0) {
        L.push_back((1.0 - 0.3 * static_cast<double>(l)) * std::polar(1.0 + 0.002 * u(rng), 2 * std::numbers::pi * i / n));
      } else if (kind == 1) {
        z += cd(0.01 * u(rng), 0.01 * u(rng));
        L.push_back(z);
      } else if (kind == 2) {
        z += cd(step(rng), step(rng));
        L.push_back(z);
      } else if (kind == 3) {
        const double tiny = coin(rng) < 3 ? std::pow(10.0, -8 - coin(rng) % 4) : 1.0;
        z += tiny * cd(step(rng), step(rng));
        L.push_back(z);
      } else {
        // A square's boundary walked in unit steps, with spikes out and back.
        const int side = std::max(1, n / 8);
        const int k = i % (4 * side), s = k / side, t = k % side;
        const cd corner[4] = {{0, 0}, {double(side), 0}, {double(side), double(side)}, {0, double(side)}};
        const cd dir[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
        const cd p = corner[s] + static_cast<double>(t) * dir[s] + static_cast<double>(l) * cd(0.5, 0.5);
        L.push_back(p);
        if (coin(rng) == 0) {
          const cd d(step(rng), step(rng));
          L.push_back(p + 2.0 * d);
          if (coin(rng) < 5) L.push_back(p + d);  // back to the middle, or on to p's successor
        }
      }
    }
  }
  return loops;
}

}  // namespace hsi::test
