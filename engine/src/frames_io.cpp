// Reading and writing .hsif frame files (layout in hsi/frames_io.h).
#include "hsi/frames_io.h"

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
  [[noreturn]] void fail(const std::string& msg) const {
    throw InputError(source + ": " + msg + " (at byte " + std::to_string(pos) + ")");
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
  for (const StoredFrame& s : f.frames) {
    if (s.map.phi.size() != K || s.map.psi.size() != K) throw InputError("frame coefficients do not match the cage");
    w.f64(s.t);
    w.u32((s.certified ? 1u : 0u) | (s.keyframe ? 2u : 0u) | (s.converged ? 4u : 0u) | (s.overlaps ? 8u : 0u));
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
  if (version != kFramesVersion)
    r.fail("unsupported frames version " + std::to_string(version) + " (this hsi reads version " + std::to_string(kFramesVersion) + ")");
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
  for (StoredFrame& s : f.frames) {
    s.t = r.f64("a frame time");
    const uint32_t flags = r.u32("frame flags");
    if (flags > 15) r.fail("unknown frame flags " + std::to_string(flags));
    s.certified = flags & 1u;
    s.keyframe = flags & 2u;
    s.converged = flags & 4u;
    s.overlaps = flags & 8u;
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
