// Writing .hsib baked sequences (layout in hsi/baked_runtime.h).
#include "hsi/baked.h"

#include <array>
#include <cstring>
#include <map>

#include "hsi/baked_runtime.h"
#include "hsi/certificate.h"
#include "hsi/map_space.h"
#include "hsi/overlap.h"
#include "hsi/samples.h"
#include "hsi/triangulate.h"

namespace hsi {

// The frame record's stop codes are NewtonStop's values (and so hsi_stop's).
static_assert(static_cast<int>(HSIB_STOP_COUNT) == kNewtonStopCount);
static_assert(HSIB_STOP_CONVERGED == static_cast<unsigned>(NewtonStop::Converged));
static_assert(HSIB_STOP_ITERATION_LIMIT == static_cast<unsigned>(NewtonStop::IterationLimit));
static_assert(HSIB_STOP_STAGNATED == static_cast<unsigned>(NewtonStop::Stagnated));
static_assert(HSIB_STOP_CERTIFICATE_REFUSED == static_cast<unsigned>(NewtonStop::CertificateRefused));
static_assert(HSIB_STOP_NO_DECREASE == static_cast<unsigned>(NewtonStop::NoDecrease));
static_assert(HSIB_STOP_NOT_FACTORED == static_cast<unsigned>(NewtonStop::NotFactored));
static_assert(HSIB_STOP_START_FOLDS == static_cast<unsigned>(NewtonStop::StartFolds));
static_assert(HSIB_STOP_START_NOT_CERTIFIED == static_cast<unsigned>(NewtonStop::StartNotCertified));
static_assert(HSIB_STOP_NOT_RECORDED >= HSIB_STOP_COUNT && HSIB_STOP_NOT_RECORDED <= 0xFFu);

namespace {

// Explicit little-endian bytes, whatever the host.
struct LEWriter {
  std::string out;
  void u32(uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
  }
  void u64(uint64_t v) {
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
  }
  void f64(double d) {
    uint64_t u;
    std::memcpy(&u, &d, 8);
    u64(u);
  }
  void f32(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    u32(u);
  }
  void point(cd p) {
    f64(p.real());
    f64(p.imag());
  }
};

// Flags 16 / 32 of frame i: the blends toward frame i + 1 at the k − 1 interior
// sub-steps, each certified (the engine's certificate: proved, not sampled) and
// checked for self-overlap. Only between two certified frames with increasing time.
std::vector<uint32_t> blend_flags(const Shape& shape, const FrameFile& frames, const BakeOptions& o) {
  const size_t F = frames.frames.size();
  std::vector<uint32_t> flags(F, 0);
  const int k = o.blend_substeps;
  if (k > 1000) throw InputError("bake: " + std::to_string(k) + " blend sub-steps per interval; at most 1000");
  if (k < 2 || F < 2) return flags;
  const Certifier certifier(shape, frames.cage, sample_boundary(shape, std::max(100, o.certificate_samples)));
  const OverlapChecker overlap(frames.cage, certifier.segments());
  const long intervals = static_cast<long>(F) - 1;
  std::string error;
#pragma omp parallel for schedule(dynamic)
  for (long i = 0; i < intervals; ++i) {
    const StoredFrame& a = frames.frames[static_cast<size_t>(i)];
    const StoredFrame& b = frames.frames[static_cast<size_t>(i) + 1];
    if (!a.certified || !b.certified || !(b.t > a.t)) continue;
    bool certified = true, overlaps = false;
    for (int j = 1; j < k && certified; ++j) {
      const double s = static_cast<double>(j) / k;
      const HarmonicMap blend{(1 - s) * a.map.phi + s * b.map.phi, (1 - s) * a.map.psi + s * b.map.psi};
      try {  // nothing may leave an OpenMP region: an error leaves the interval unflagged, and is reported below
        certified = certifier.certify(blend).certified;
        overlaps = overlaps || overlap.check(blend).overlaps();
      } catch (const std::exception& e) {
        certified = false;
#pragma omp critical(hsi_bake_error)
        if (error.empty()) error = "bake: certifying the blends after frame " + std::to_string(i) + ": " + e.what();
      }
    }
    if (certified) flags[static_cast<size_t>(i)] = HSIB_FRAME_BLEND_CERTIFIED | (overlaps ? HSIB_FRAME_BLEND_OVERLAPS : 0u);
  }
  if (!error.empty()) throw InputError(error);
  return flags;
}

}  // namespace

std::string encode_baked(const Shape& shape, const FrameFile& frames, const BakeOptions& options) {
  const Cage& cage = frames.cage;
  if (cage.loops.empty()) throw InputError("bake: the frames have no cage");
  const MapSpace space(cage, Gauge::ModuloRigid);
  const int m = cage.vertex_count(), N = cage.hole_count(), n = space.n();

  // Runtime rows: Re C_j and Im C_j per active cage column, log|w − ρ_h| per hole.
  std::vector<uint32_t> row_sources;
  std::vector<std::array<int, 2>> rows_of(static_cast<size_t>(n));  // active column → (row of Re C, row of Im C or −1)
  for (int a = 0; a < n; ++a) {
    const int j = space.active()[static_cast<size_t>(a)];
    if (j < m) {
      rows_of[static_cast<size_t>(a)] = {static_cast<int>(row_sources.size()), static_cast<int>(row_sources.size()) + 1};
      row_sources.push_back(static_cast<uint32_t>(j) << 2);
      row_sources.push_back((static_cast<uint32_t>(j) << 2) | 1u);
    } else {
      rows_of[static_cast<size_t>(a)] = {static_cast<int>(row_sources.size()), -1};
      row_sources.push_back((static_cast<uint32_t>(j - m) << 2) | 2u);
    }
  }
  // E: x ↦ row weights. v = T x holds (Re φ_a, Im φ_a, Re ψ_a, Im ψ_a); the row of
  // Re C weighs φ + conj ψ, the row of Im C weighs i (φ − conj ψ) (f = Σ C φ + conj Σ C ψ).
  struct Entry {
    uint32_t target, source;
    double value;
  };
  std::vector<Entry> expansion;
  const Eigen::SparseMatrix<double>& T = space.T();
  for (int k = 0; k < T.outerSize(); ++k) {
    std::map<uint32_t, double> column;
    for (Eigen::SparseMatrix<double>::InnerIterator it(T, k); it; ++it) {
      const int part = static_cast<int>(it.row()) / n, a = static_cast<int>(it.row()) % n;
      const double v = it.value();
      const int rc = rows_of[static_cast<size_t>(a)][0], rs = rows_of[static_cast<size_t>(a)][1];
      auto add = [&](int row, int comp, double value) {
        if (row >= 0) column[static_cast<uint32_t>(2 * row + comp)] += value;
      };
      switch (part) {
        case 0: add(rc, 0, v); add(rs, 1, v); break;    // Re φ
        case 1: add(rc, 1, v); add(rs, 0, -v); break;   // Im φ
        case 2: add(rc, 0, v); add(rs, 1, -v); break;   // Re ψ
        default: add(rc, 1, -v); add(rs, 0, -v); break; // Im ψ
      }
    }
    for (const auto& [target, value] : column)
      if (value != 0) expansion.push_back({target, static_cast<uint32_t>(k), value});
  }

  const uint32_t R = static_cast<uint32_t>(row_sources.size()), D = static_cast<uint32_t>(space.dim());
  const uint32_t scalar = options.single_precision ? 4 : 8;
  const uint32_t S = 48 + D * scalar + 4;

  LEWriter st;
  for (const Loop& l : cage.loops) st.u32(static_cast<uint32_t>(l.size()));
  for (const Loop& l : cage.loops)
    for (const cd& z : l) st.point(z);
  for (const cd& p : cage.hole_points) st.point(p);
  for (uint32_t r : row_sources) st.u32(r);
  for (const Entry& e : expansion) {
    st.u32(e.target);
    st.u32(e.source);
    st.f64(e.value);
  }
  // v2: the outline, the texture rectangle and the triangulation.
  for (int l = 0; l < shape.loop_count(); ++l) st.u32(static_cast<uint32_t>(shape.loop(l).size()));
  uint32_t Ms = 0;
  for (int l = 0; l < shape.loop_count(); ++l)
    for (const cd& p : shape.loop(l)) {
      st.point(p);
      ++Ms;
    }
  const BoundingBox bb = bounding_box(shape);
  const std::array<double, 4> rect = options.texture_rect.value_or(std::array<double, 4>{bb.lo.real(), bb.lo.imag(), bb.hi.real(), bb.hi.imag()});
  if (!(rect[2] > rect[0]) || !(rect[3] > rect[1])) throw InputError("bake: the texture rectangle is empty");
  for (double r : rect) st.f64(r);
  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(shape, std::max(16, options.mesh_vertices));
  const TriMesh mesh = triangulate(shape, to);
  for (const cd& v : mesh.vertices) {
    st.f32(static_cast<float>(v.real()));
    st.f32(static_cast<float>(v.imag()));
  }
  for (const auto& t : mesh.triangles)
    for (int v : t) st.u32(static_cast<uint32_t>(v));

  std::vector<uint32_t> stop_words(frames.frames.size(), 0);  // 0: not recorded; else 0x100 | the stop code
  for (size_t i = 0; i < frames.frames.size(); ++i) {
    if (frames.frames[i].map.phi.size() != basis_size(cage) || frames.frames[i].map.psi.size() != basis_size(cage))
      throw InputError("bake: frame " + std::to_string(i) + " has " + std::to_string(frames.frames[i].map.phi.size()) +
                       " coefficients; the cage needs " + std::to_string(basis_size(cage)));
    std::optional<NewtonStop> stop;
    try {
      stop = stored_stop(frames.frames[i], i);
    } catch (const InputError& e) {
      throw InputError(std::string("bake: ") + e.what());
    }
    if (stop) stop_words[i] = 0x100u | static_cast<uint32_t>(*stop);
  }
  const std::vector<uint32_t> blends = blend_flags(shape, frames, options);

  LEWriter fr;
  for (size_t i = 0; i < frames.frames.size(); ++i) {
    const StoredFrame& f = frames.frames[i];
    if (i > 0 && !(f.t >= frames.frames[i - 1].t)) throw InputError("bake: frame times must not decrease (frame " + std::to_string(i) + ")");
    MapSpace::Canonical c;
    try {
      c = space.reduce(f.map);
    } catch (const InputError& e) {
      throw InputError("bake: frame " + std::to_string(i) + ": " + e.what());
    }
    const size_t start = fr.out.size();
    fr.f64(f.t);
    fr.u32((f.certified ? 1u : 0u) | (f.keyframe ? 2u : 0u) | (f.converged ? 4u : 0u) | (f.overlaps ? 8u : 0u) | blends[i]);
    fr.u32(stop_words[i]);
    fr.point(c.rotation);
    fr.point(c.translation);
    for (Eigen::Index d = 0; d < c.x.size(); ++d) {
      if (options.single_precision)
        fr.f32(static_cast<float>(c.x(d)));
      else
        fr.f64(c.x(d));
    }
    fr.u32(hsib_crc32(fr.out.data() + start, fr.out.size() - start));
  }

  LEWriter h;
  h.out = "HSIB";
  h.u32(HSIB_FORMAT_VERSION);
  h.u32(HSIB_HEADER_SIZE);
  h.u32(options.single_precision ? 1u : 0u);
  h.u32(static_cast<uint32_t>(cage.loops.size()));
  h.u32(static_cast<uint32_t>(m));
  h.u32(static_cast<uint32_t>(N));
  h.u32(R);
  h.u32(D);
  h.u32(static_cast<uint32_t>(expansion.size()));
  h.u32(static_cast<uint32_t>(frames.frames.size()));
  h.u32(S);
  h.f64(bb.lo.real());
  h.f64(bb.lo.imag());
  h.f64(bb.hi.real());
  h.f64(bb.hi.imag());
  h.u64(st.out.size());
  h.u32(hsib_crc32(st.out.data(), st.out.size()));
  h.u32(static_cast<uint32_t>(std::max(0, options.blend_substeps)));
  h.u32(static_cast<uint32_t>(mesh.vertices.size()));
  h.u32(static_cast<uint32_t>(mesh.triangles.size()));
  h.u32(static_cast<uint32_t>(shape.loop_count()));
  h.u32(Ms);
  for (int r = 0; r < 3; ++r) h.u32(0);
  h.u32(hsib_crc32(h.out.data(), h.out.size()));
  return h.out + st.out + fr.out;
}

void write_baked(const std::filesystem::path& path, const Shape& shape, const FrameFile& frames, const BakeOptions& options) {
  write_file_atomic(path, encode_baked(shape, frames, options));
}

}  // namespace hsi
