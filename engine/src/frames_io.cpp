// Reading and writing .hsif frame files (layout in hsi/frames_io.h).
#include "hsi/frames_io.h"

#include <array>
#include <cstring>
#include <fstream>
#include <sstream>

namespace hsi {
namespace {

class Writer {
 public:
  void u32(uint32_t v) { raw(&v, 4); }
  void f64(double v) { raw(&v, 8); }
  void point(cd p) {
    f64(p.real());
    f64(p.imag());
  }
  void raw(const void* p, size_t n) { out.append(static_cast<const char*>(p), n); }
  std::string out;
};

class Reader {
 public:
  Reader(const std::string& b, const std::string& s) : bytes(b), source(s) {}
  uint32_t u32(const char* what) {
    uint32_t v;
    take(&v, 4, what);
    return v;
  }
  double f64(const char* what) {
    double v;
    take(&v, 8, what);
    return v;
  }
  cd point(const char* what) {
    const double x = f64(what);
    return {x, f64(what)};
  }
  [[noreturn]] void fail(const std::string& msg) const { fail_at(msg, pos); }
  [[noreturn]] void fail_at(const std::string& msg, size_t at) const {
    throw InputError(source + ": " + msg + " (at byte " + std::to_string(at) + ")");
  }
  void need(size_t n, const char* what) const {
    if (bytes.size() - pos < n)
      throw InputError(source + ": truncated: needs " + std::to_string(n) + " more bytes for " + what + " at byte " +
                       std::to_string(pos) + ", file has " + std::to_string(bytes.size()));
  }
  size_t remaining() const { return bytes.size() - pos; }
  size_t pos = 0;

 private:
  void take(void* p, size_t n, const char* what) {
    need(n, what);
    std::memcpy(p, bytes.data() + pos, n);
    pos += n;
  }
  const std::string& bytes;
  std::string source;
};

}  // namespace

std::optional<NewtonStop> stored_stop(const StoredFrame& f, size_t index) {
  if (!f.stop) return f.converged ? std::optional<NewtonStop>(NewtonStop::Converged) : std::nullopt;
  if ((*f.stop == NewtonStop::Converged) != f.converged)
    throw InputError("frame " + std::to_string(index) + ": its stop reason '" + to_string(*f.stop) + "' contradicts its converged flag (" +
                     (f.converged ? "set" : "clear") + ")");
  return f.stop;
}

const char* stop_name(const std::optional<NewtonStop>& stop) { return stop ? to_string(*stop) : "not recorded"; }

std::string stop_counts(const std::vector<StoredFrame>& frames) {
  std::vector<std::optional<NewtonStop>> stops;
  for (size_t i = 0; i < frames.size(); ++i) stops.push_back(stored_stop(frames[i], i));
  return stop_counts(stops);
}

std::string stop_counts(const std::vector<std::optional<NewtonStop>>& stops) {
  std::array<size_t, kNewtonStopCount + 1> n{};  // the last: not recorded
  for (const std::optional<NewtonStop>& stop : stops) ++n[stop ? static_cast<size_t>(*stop) : static_cast<size_t>(kNewtonStopCount)];
  std::string out;
  for (size_t k = 1; k < n.size(); ++k)
    if (n[k] > 0) {
      const std::optional<NewtonStop> stop = k < static_cast<size_t>(kNewtonStopCount) ? std::optional(static_cast<NewtonStop>(k)) : std::nullopt;
      out += (out.empty() ? "" : ", ") + std::to_string(n[k]) + " " + stop_name(stop);
    }
  return out;
}

std::string encode_frames(const FrameFile& f) {
  Writer w;
  w.raw("HSIF", 4);
  w.u32(kFramesVersion);
  w.u32(static_cast<uint32_t>(f.cage.loops.size()));
  for (const Loop& l : f.cage.loops) {
    w.u32(static_cast<uint32_t>(l.size()));
    for (const cd& p : l) w.point(p);
  }
  w.u32(static_cast<uint32_t>(f.cage.hole_points.size()));
  for (const cd& p : f.cage.hole_points) w.point(p);
  const uint32_t K = static_cast<uint32_t>(basis_size(f.cage));
  w.u32(K);
  w.u32(static_cast<uint32_t>(f.frames.size()));
  for (size_t i = 0; i < f.frames.size(); ++i) {
    const StoredFrame& s = f.frames[i];
    if (s.map.phi.size() != K || s.map.psi.size() != K) throw InputError("frame coefficients do not match the cage");
    const std::optional<NewtonStop> stop = stored_stop(s, i);
    const uint32_t code = stop ? static_cast<uint32_t>(*stop) : kFramesStopNotRecorded;
    w.f64(s.t);
    w.u32((s.certified ? 1u : 0u) | (s.keyframe ? 2u : 0u) | (s.converged ? 4u : 0u) | (s.overlaps ? 8u : 0u) | (code << 8));
    w.u32(s.iterations);
    w.f64(s.energy);
    for (Eigen::Index j = 0; j < K; ++j) w.point(s.map.phi(j));
    for (Eigen::Index j = 0; j < K; ++j) w.point(s.map.psi(j));
  }
  return w.out;
}

FrameFile decode_frames(const std::string& bytes, const std::string& source) {
  Reader r(bytes, source);
  r.need(4, "the magic \"HSIF\"");
  if (bytes.compare(0, 4, "HSIF") != 0) r.fail("not an hsi frames file (magic is not \"HSIF\")");
  r.pos = 4;
  const uint32_t version = r.u32("the version");
  if (version != 1 && version != kFramesVersion)
    r.fail("unsupported frames version " + std::to_string(version) + " (this hsi reads versions 1 and " + std::to_string(kFramesVersion) + ")");
  FrameFile f;
  const uint32_t L = r.u32("the loop count");
  if (L < 1 || L > 100000) r.fail("impossible cage loop count " + std::to_string(L));
  for (uint32_t l = 0; l < L; ++l) {
    const uint32_t n = r.u32("a cage loop size");
    if (n < 3) r.fail("impossible cage loop size " + std::to_string(n));
    if (n > r.remaining() / 16)
      r.fail("truncated: cage loop " + std::to_string(l) + " announces " + std::to_string(n) + " vertices, only " +
             std::to_string(r.remaining()) + " bytes remain");
    Loop loop(n);
    for (cd& p : loop) {
      p = r.point("a cage vertex");
      if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) r.fail("non-finite cage vertex in loop " + std::to_string(l));
    }
    f.cage.loops.push_back(std::move(loop));
  }
  const uint32_t N = r.u32("the hole count");
  if (N != L - 1) r.fail("hole point count " + std::to_string(N) + " does not match " + std::to_string(L - 1) + " hole loops");
  for (uint32_t h = 0; h < N; ++h) {
    f.cage.hole_points.push_back(r.point("a hole point"));
    if (!std::isfinite(f.cage.hole_points.back().real()) || !std::isfinite(f.cage.hole_points.back().imag()))
      r.fail("non-finite hole point " + std::to_string(h + 1));
  }
  const uint32_t K = r.u32("the coefficient count");
  if (K != static_cast<uint32_t>(basis_size(f.cage)))
    r.fail("coefficient count " + std::to_string(K) + " does not match the cage (" + std::to_string(basis_size(f.cage)) + ")");
  const uint32_t F = r.u32("the frame count");
  const size_t per_frame = 24 + 32 * static_cast<size_t>(K);
  if (static_cast<size_t>(F) * per_frame != r.remaining())
    r.fail("frame data is " + std::to_string(r.remaining()) + " bytes; " + std::to_string(F) + " frames need " +
           std::to_string(static_cast<size_t>(F) * per_frame) + (static_cast<size_t>(F) * per_frame > r.remaining() ? " (truncated)" : " (trailing bytes)"));
  f.frames.resize(F);
  for (uint32_t i = 0; i < F; ++i) {
    StoredFrame& s = f.frames[i];
    const std::string frame = "frame " + std::to_string(i) + ": ";
    s.t = r.f64("a frame time");
    const size_t flags_at = r.pos;
    const uint32_t flags = r.u32("frame flags");
    // Version 1: bits 0..3; version 2: and the stop code in bits 8..15 (layout in frames_io.h).
    const uint32_t known = version == 1 ? 15u : 0xFF0Fu;
    if (flags & ~known) r.fail_at(frame + "unknown frame flags " + std::to_string(flags), flags_at);
    s.certified = flags & 1u;
    s.keyframe = flags & 2u;
    s.converged = flags & 4u;
    s.overlaps = flags & 8u;
    if (version == 1) {
      s.stop = s.converged ? std::optional<NewtonStop>(NewtonStop::Converged) : std::nullopt;
    } else {
      const uint32_t code = (flags >> 8) & 0xFFu;
      if (code >= static_cast<uint32_t>(kNewtonStopCount) && code != kFramesStopNotRecorded)
        r.fail_at(frame + "unknown stop code " + std::to_string(code) + " (bits 8..15 of the frame flags; known: 0.." +
                      std::to_string(kNewtonStopCount - 1) + " and " + std::to_string(kFramesStopNotRecorded) + ", not recorded)",
                  flags_at);
      if (code != kFramesStopNotRecorded) s.stop = static_cast<NewtonStop>(code);
      if ((code == 0) != s.converged)
        r.fail_at(frame + "stop code " + std::to_string(code) + " (" + stop_name(s.stop) + ") contradicts the converged flag 4 (" +
                      (s.converged ? "set" : "clear") + ")",
                  flags_at);
    }
    s.iterations = r.u32("an iteration count");
    s.energy = r.f64("an energy");
    s.map.phi.resize(K);
    s.map.psi.resize(K);
    for (uint32_t j = 0; j < K; ++j) s.map.phi(j) = r.point("phi");
    for (uint32_t j = 0; j < K; ++j) s.map.psi(j) = r.point("psi");
    if (!std::isfinite(s.t) || !s.map.phi.allFinite() || !s.map.psi.allFinite()) r.fail("non-finite values in a frame");
  }
  return f;
}

void write_frames(const std::filesystem::path& path, const FrameFile& file) { write_file_atomic(path, encode_frames(file)); }

FrameFile read_frames(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the frames file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return decode_frames(ss.str(), path.string());
}

}  // namespace hsi
