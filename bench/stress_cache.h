// The keyframe cache of the Newton stress benchmark (bench_stress --keyframes-cache):
// keyframes authored once from a sequence's handles and targets (stress::author, the
// slow part of a corpus run) are kept in a binary file and reused while the inputs that
// made them are the same. An entry is keyed by the sequence id, |G| and a hash of those
// inputs (the shape's scene file, handles, targets, times, the authoring options and
// this format's version); an entry whose hash differs is stale and is authored again.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "stress_corpus.h"

namespace hsi::stress {

// 64-bit FNV-1a over bytes; doubles enter by their bit pattern, so any change of an
// input, even in the last bit, changes the key.
class InputHash {
 public:
  void bytes(const void* p, size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ c[i]) * 0x100000001b3ULL;
  }
  void str(const std::string& s) {
    u64(s.size());
    bytes(s.data(), s.size());
  }
  void u64(uint64_t v) { bytes(&v, sizeof v); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void point(cd p) {
    f64(p.real());
    f64(p.imag());
  }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ULL;
};

// One authored keyframe as the benchmark needs it.
struct CachedKeyframe {
  double time = 0;
  bool reached = true;        // the targets were reached (else the closest certified map)
  double target_error = 0;    // max distance handle to target, relative to the shape's size
  HarmonicMap map;
};

struct CacheEntry {
  std::string id;
  int samples = 0;
  uint64_t hash = 0;
  double ms = 0;  // authoring time (solver) when it was made
  std::vector<CachedKeyframe> keyframes;
};

class KeyframeCache {
 public:
  static constexpr char kMagic[8] = {'H', 'S', 'I', 'K', 'F', 'C', '1', '\n'};

  // An absent file is an empty cache; a file that is not a cache, or is cut short, is
  // an error naming it (never silently replaced).
  void load(const std::filesystem::path& file) {
    entries_.clear();
    std::ifstream in(file, std::ios::binary);
    if (!in) return;
    auto fail = [&](const std::string& why) {
      throw std::runtime_error("keyframe cache " + file.string() + ": " + why + " (delete it to author every keyframe again)");
    };
    char magic[8];
    if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) fail("not an hsi keyframe cache (version 1)");
    const uint64_t count = get<uint64_t>(in);
    for (uint64_t e = 0; e < count && in; ++e) {
      CacheEntry c;
      const uint64_t id_size = get<uint64_t>(in);
      if (id_size > 4096) fail("entry " + std::to_string(e) + " is damaged");
      c.id.resize(id_size);
      in.read(c.id.data(), static_cast<std::streamsize>(id_size));
      c.samples = static_cast<int>(get<int64_t>(in));
      c.hash = get<uint64_t>(in);
      c.ms = get<double>(in);
      const uint64_t keys = get<uint64_t>(in);
      if (keys > 64) fail("entry " + c.id + " is damaged");
      for (uint64_t k = 0; k < keys && in; ++k) {
        CachedKeyframe kf;
        kf.time = get<double>(in);
        kf.reached = get<uint64_t>(in) != 0;
        kf.target_error = get<double>(in);
        const uint64_t m = get<uint64_t>(in);
        if (m > (1u << 20)) fail("entry " + c.id + " is damaged");
        kf.map.phi.resize(static_cast<Eigen::Index>(m));
        kf.map.psi.resize(static_cast<Eigen::Index>(m));
        in.read(reinterpret_cast<char*>(kf.map.phi.data()), static_cast<std::streamsize>(m * sizeof(cd)));
        in.read(reinterpret_cast<char*>(kf.map.psi.data()), static_cast<std::streamsize>(m * sizeof(cd)));
        c.keyframes.push_back(std::move(kf));
      }
      if (!in) fail("cut short in entry " + std::to_string(e));
      entries_[{c.id, c.samples}] = std::move(c);
    }
    if (!in) fail("cut short");
  }

  // Entries in (id, |G|) order, so the same keyframes give the same file. Written to a
  // temporary file and renamed: a run killed while saving keeps the previous cache.
  void save(const std::filesystem::path& file) const {
    const std::filesystem::path tmp = file.string() + ".tmp";
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      out.write(kMagic, 8);
      put<uint64_t>(out, entries_.size());
      for (const auto& [key, c] : entries_) {
        put<uint64_t>(out, c.id.size());
        out.write(c.id.data(), static_cast<std::streamsize>(c.id.size()));
        put<int64_t>(out, c.samples);
        put<uint64_t>(out, c.hash);
        put<double>(out, c.ms);
        put<uint64_t>(out, c.keyframes.size());
        for (const CachedKeyframe& kf : c.keyframes) {
          put<double>(out, kf.time);
          put<uint64_t>(out, kf.reached ? 1 : 0);
          put<double>(out, kf.target_error);
          put<uint64_t>(out, static_cast<uint64_t>(kf.map.phi.size()));
          out.write(reinterpret_cast<const char*>(kf.map.phi.data()), static_cast<std::streamsize>(kf.map.phi.size() * sizeof(cd)));
          out.write(reinterpret_cast<const char*>(kf.map.psi.data()), static_cast<std::streamsize>(kf.map.psi.size() * sizeof(cd)));
        }
      }
      if (!out) throw std::runtime_error("cannot write the keyframe cache " + tmp.string());
    }
    std::filesystem::rename(tmp, file);
  }

  // The entry for (id, |G|) if its hash matches; else null (absent or stale).
  const CacheEntry* find(const std::string& id, int samples, uint64_t hash) const {
    const auto it = entries_.find({id, samples});
    return it != entries_.end() && it->second.hash == hash ? &it->second : nullptr;
  }
  bool has_stale(const std::string& id, int samples, uint64_t hash) const {
    const auto it = entries_.find({id, samples});
    return it != entries_.end() && it->second.hash != hash;
  }
  void put(CacheEntry c) {
    const std::pair<std::string, int> key{c.id, c.samples};
    entries_[key] = std::move(c);
  }
  size_t size() const { return entries_.size(); }

 private:
  template <class T>
  static T get(std::istream& in) {
    T v{};
    in.read(reinterpret_cast<char*>(&v), sizeof v);
    return v;
  }
  template <class T>
  static void put(std::ostream& out, T v) {
    out.write(reinterpret_cast<const char*>(&v), sizeof v);
  }
  std::map<std::pair<std::string, int>, CacheEntry> entries_;
};

// The key of a sequence's keyframes: everything stress::author's result depends on
// that a corpus edit can change. The solver's code is not in it: after a change to
// authoring (keyframes.cpp, newton.cpp), delete the cache.
inline uint64_t keyframes_hash(const std::string& scene_file_contents, const Sequence& q, int samples,
                               const KeyframeOptions& o = {}) {
  InputHash h;
  h.str("hsi stress keyframes v1");
  h.str(scene_file_contents);
  h.str(q.id);
  h.u64(static_cast<uint64_t>(samples));
  h.u64(q.handles.size());
  for (cd p : q.handles) h.point(p);
  h.u64(q.targets.size());
  for (size_t k = 0; k < q.targets.size(); ++k) {
    h.f64(q.times[k]);
    h.u64(q.targets[k].size());
    for (cd p : q.targets[k]) h.point(p);
  }
  h.f64(o.lambda);
  h.u64(static_cast<uint64_t>(o.stages));
  h.u64(static_cast<uint64_t>(o.stage_iterations));
  h.u64(static_cast<uint64_t>(o.newton.max_iterations));
  h.f64(o.newton.tolerance);
  h.f64(o.reach_tolerance);
  return h.value();
}

// Why a sequence's keyframes do not all pass today's certificate ("keyframe k: reason"),
// or empty when every one does. The cache key does not cover the solver's code: a
// keyframe authored before a change to the certificate may now fail it (one authored
// at a margin within round-off, before the certificate counted its own rounding), and
// bench_stress then authors the sequence again instead of failing its runs.
// Also stale: a keyframe whose coefficients in the interpolation's reduced space
// (metric_space.reduce, then expand: what every frame after it starts from) the
// certificate refuses, as one authored at the fold limit before authoring kept a margin
// (NewtonOptions::min_margin; grid_6/bend_steps).
inline std::string uncertified_keyframe(const ShapeSetup& setup, const Authored& a) {
  for (size_t k = 0; k < a.maps.size(); ++k) {
    const CertificateResult c = setup.certifier.certify(a.maps[k]);
    if (!c.certified) return "keyframe " + std::to_string(k) + ": " + c.reason;
    Eigen::VectorXd x;
    try {
      x = setup.metric_space.reduce(a.maps[k]).x;
    } catch (const InputError&) {
      continue;  // a map outside the map space: the Interpolator names it
    }
    const CertificateResult r = setup.certifier.certify(setup.metric_space.expand(x));
    if (!r.certified) return "keyframe " + std::to_string(k) + "'s reduced coefficients: " + r.reason;
  }
  return {};
}

inline CacheEntry to_entry(const std::string& id, int samples, uint64_t hash, const Authored& a) {
  CacheEntry c{id, samples, hash, a.ms, {}};
  for (size_t k = 0; k < a.maps.size(); ++k) c.keyframes.push_back({a.times[k], a.reached[k] != 0, a.target_error[k], a.maps[k]});
  return c;
}

inline Authored from_entry(const CacheEntry& c) {
  Authored a;
  a.ms = c.ms;
  for (const CachedKeyframe& k : c.keyframes) {
    a.times.push_back(k.time);
    a.maps.push_back(k.map);
    a.reached.push_back(k.reached);
    a.target_error.push_back(k.target_error);
    a.unreached += !k.reached;
    a.max_target_error = std::max(a.max_target_error, k.target_error);
  }
  return a;
}

}  // namespace hsi::stress
