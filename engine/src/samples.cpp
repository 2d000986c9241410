// Arc-length sampling of the boundary loops.
#include "hsi/samples.h"

#include <algorithm>
#include <cmath>

namespace hsi {

BoundarySamples sample_boundary(const Shape& shape, int count) {
  if (count < 1) throw InputError("the number of boundary samples must be positive (got " + std::to_string(count) + ")");
  const int loops = shape.loop_count();
  std::vector<double> len(static_cast<size_t>(loops));
  double total = 0;
  for (int l = 0; l < loops; ++l) total += len[static_cast<size_t>(l)] = perimeter(shape.loop(l));
  // Largest-remainder split of count by length, at least 8 per loop.
  std::vector<int> per(static_cast<size_t>(loops));
  std::vector<std::pair<double, int>> rem;
  int assigned = 0;
  for (int l = 0; l < loops; ++l) {
    const double exact = count * len[static_cast<size_t>(l)] / total;
    per[static_cast<size_t>(l)] = std::max(8, static_cast<int>(std::floor(exact)));
    assigned += per[static_cast<size_t>(l)];
    rem.push_back({exact - std::floor(exact), l});
  }
  std::sort(rem.begin(), rem.end(), [](auto a, auto b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
  for (size_t k = 0; assigned < count && k < rem.size(); ++k, ++assigned) ++per[static_cast<size_t>(rem[k].second)];

  BoundarySamples s;
  for (int l = 0; l < loops; ++l) {
    const Loop& loop = shape.loop(l);
    const int n = static_cast<int>(loop.size());
    const int m = per[static_cast<size_t>(l)];
    const double step = len[static_cast<size_t>(l)] / m;
    s.loop_begin.push_back(static_cast<int>(s.points.size()));
    int e = 0;
    double edge_start = 0;  // arc length at the start of edge e
    for (int k = 0; k < m; ++k) {
      const double target = (k + 0.5) * step;
      double elen = std::abs(loop[static_cast<size_t>((e + 1) % n)] - loop[static_cast<size_t>(e)]);
      while (edge_start + elen < target && e < n - 1) {
        edge_start += elen;
        ++e;
        elen = std::abs(loop[static_cast<size_t>((e + 1) % n)] - loop[static_cast<size_t>(e)]);
      }
      const double t = std::clamp((target - edge_start) / elen, 0.0, 1.0);
      const cd a = loop[static_cast<size_t>(e)], b = loop[static_cast<size_t>((e + 1) % n)];
      s.points.push_back(a + t * (b - a));
      s.loop.push_back(l);
      s.edge.push_back(e);
    }
  }
  s.loop_begin.push_back(static_cast<int>(s.points.size()));
  return s;
}

std::vector<int> hessian_subset(const BoundarySamples& g, double ratio, const std::vector<int>& min_per_loop) {
  if (!(ratio > 0 && ratio <= 1))
    throw InputError("the Hessian sample ratio must lie in (0, 1] (got " + std::to_string(ratio) + ")");
  std::vector<int> idx;
  const size_t loops = g.loop_begin.size() - 1;
  for (size_t l = 0; l < loops; ++l) {
    const size_t begin = static_cast<size_t>(g.loop_begin[l]), n = static_cast<size_t>(g.loop_begin[l + 1]) - begin;
    size_t m = std::max<size_t>(1, static_cast<size_t>(std::llround(ratio * static_cast<double>(n))));
    if (l < min_per_loop.size()) m = std::max(m, static_cast<size_t>(std::max(0, min_per_loop[l])));
    m = std::min(m, n);
    for (size_t k = 0; k < m; ++k) idx.push_back(static_cast<int>(begin + (k * n) / m));
  }
  return idx;
}

}  // namespace hsi
