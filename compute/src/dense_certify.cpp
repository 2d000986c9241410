// Host side of dense certification (see dense_certify.h and shaders/certify.comp):
// the segments are uploaded once per shape; per map, the coefficients and upper
// bounds of the summation-by-parts jumps |S_j| go up, two dispatches run (values at
// the breakpoints, then the segments with subdivision) and the per-segment outcomes
// come back to be reduced by hsi::reduce_certificate, as on the CPU.
#include "hsi/compute/dense_certify.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "hsi/compute/spirv/certify_f64.h"
#include "timing.h"

namespace hsi::compute {

namespace {

// Mirrors `Push` in certify.comp.
struct PushConstants {
  uint32_t mode, count, cage_loops, hole_count;
  uint32_t vertex_count, cage_at, holes_at, phi_at;
  uint32_t psi_at, jumps_at, max_depth, max_pieces;
  uint32_t flags, diff_at, pad1, pad2;
};
static_assert(sizeof(PushConstants) == 64);
constexpr uint32_t kModeValues = 0, kModeSegments = 1, kModeBasis = 2, kModeBasisValues = 3;
constexpr uint32_t kStopAtFirstFailure = 1, kHaveLip = 2;
constexpr uint32_t kWorkgroupSize = 64;  // local_size_x in the shader
constexpr uint32_t kRowsPerGroup = 8;    // mode 3: breakpoints per workgroup (kRows in the shader)
constexpr VkDeviceSize kBasisEntryBytes = 64;  // `BasisEntry` in certify.comp (std430)

// Mirrors `SegmentOut` in certify.comp (std430).
struct SegmentOut {
  double arg, margin, sigma1, sigma2, k, fail_x, fail_y, abs_a, abs_b;
  uint32_t status, pieces;
};
static_assert(sizeof(SegmentOut) == 80);
constexpr VkDeviceSize kValuesBytes = 96;  // `Values` in certify.comp: 4 dvec2 + dvec4 (std430)

enum Binding : uint32_t { kLoops, kGeom, kPoints, kNext, kValues, kOut, kControl, kLip, kBasis, kBindingCount };
constexpr std::array<VkDescriptorType, kBindingCount> kBindings = {
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

Buffer upload_buffer(const Context& ctx, const void* data, VkDeviceSize bytes) {
  Buffer b(ctx, std::max<VkDeviceSize>(bytes, 64), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
  b.write(data, bytes);
  return b;
}

}  // namespace

DenseCertifier::DenseCertifier(const Context& context, const Shape& shape, const Cage& cage,
                               const BoundarySamples& samples, const DenseCertifyOptions& options)
    : context_(&context), cage_(cage), segments_(certificate_segments(shape, samples)) {
  if (!context.info().float64)
    throw VulkanError("dense certification needs double precision (shaderFloat64), which " + context.info().name +
                      " does not offer; use the CPU hsi::Certifier on this machine");
  if (cage.loops.empty() || cage.vertex_count() == 0) throw InputError("dense certification: the cage has no vertices");
  for (size_t l = 0; l < cage.loops.size(); ++l)
    if (cage.loops[l].size() < 2)
      throw InputError("dense certification: cage " + loop_name(static_cast<int>(l)) + " has " +
                       std::to_string(cage.loops[l].size()) + " vertices; a cage loop needs at least 2");
  if (static_cast<int>(cage.loops.size()) != shape.loop_count() || cage.hole_count() != shape.loop_count() - 1)
    throw InputError("dense certification: the cage has " + std::to_string(cage.loops.size()) + " loops and " +
                     std::to_string(cage.hole_count()) + " hole points but the shape has " +
                     std::to_string(shape.loop_count()) + " loops");
  const size_t S = segments_.size();
  if (S == 0) throw InputError("dense certification: the shape has no boundary segments");
  if (S > std::numeric_limits<uint32_t>::max() / kWorkgroupSize ||
      S * kValuesBytes > context.info().max_storage_buffer_range)
    throw InputError("dense certification: " + std::to_string(S) + " boundary segments exceed what " +
                     context.info().name + " can hold in one storage buffer");

  pipeline_ = ComputePipeline(context, certify_f64, kBindings, sizeof(PushConstants));
  set_ = DescriptorSet(context, pipeline_.layout());

  int first = 0;
  for (const Loop& loop : cage.loops) {
    loops_host_.push_back(static_cast<uint32_t>(first));
    loops_host_.push_back(static_cast<uint32_t>(loop.size()));
    first += static_cast<int>(loop.size());
  }
  loops_ = upload_buffer(context, loops_host_.data(), loops_host_.size() * sizeof(uint32_t));
  std::vector<double> pts;
  pts.reserve(2 * S);
  for (const cd& p : segments_.points) {
    pts.push_back(p.real());
    pts.push_back(p.imag());
  }
  points_ = upload_buffer(context, pts.data(), pts.size() * sizeof(double));
  std::vector<uint32_t> next(segments_.next.begin(), segments_.next.end());
  next_ = upload_buffer(context, next.data(), next.size() * sizeof(uint32_t));

  values_ = Buffer(context, S * kValuesBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kDeviceLocal);
  out_ = Buffer(context, S * sizeof(SegmentOut), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                MemoryUse::kDeviceLocal);
  // Read in place only from cached host-visible memory (CPU devices, integrated GPUs).
  if (!(out_.host_visible() && (out_.memory_flags() & VK_MEMORY_PROPERTY_HOST_CACHED_BIT)))
    readback_ = Buffer(context, S * sizeof(SegmentOut), VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::kReadback);
  control_ = Buffer(context, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                    MemoryUse::kDeviceLocal);

  lip_ = Buffer(context, S * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kDeviceLocal);

  // The basis matrix, where it fits: computed here once (mode 2).
  const uint64_t cols = static_cast<uint64_t>(cage.vertex_count() + cage.hole_count());
  const uint64_t entries = static_cast<uint64_t>(S) * cols;
  const VkDeviceSize basis_bytes = entries * kBasisEntryBytes;
  const bool fits = basis_bytes <= options.max_basis_bytes && basis_bytes <= context.info().max_storage_buffer_range &&
                    entries <= std::numeric_limits<uint32_t>::max() - kWorkgroupSize;
  if (fits) basis_ = Buffer(context, basis_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kDeviceLocal);
  // Unused bindings still need a buffer.
  set_.bind(kLoops, loops_);
  set_.bind(kPoints, points_);
  set_.bind(kNext, next_);
  set_.bind(kValues, values_);
  set_.bind(kOut, out_);
  set_.bind(kControl, control_);
  set_.bind(kLip, lip_);
  set_.bind(kBasis, basis_ ? basis_ : lip_);
  if (!fits) return;

  std::vector<double> geom;  // the cage and hole points, where record() puts them too
  for (const Loop& loop : cage.loops)
    for (const cd& z : loop) {
      geom.push_back(z.real());
      geom.push_back(z.imag());
    }
  for (const cd& rho : cage.hole_points) {
    geom.push_back(rho.real());
    geom.push_back(rho.imag());
  }
  geom_ = upload_buffer(context, geom.data(), geom.size() * sizeof(double));
  set_.bind(kGeom, geom_);
  PushConstants pc{};
  pc.mode = kModeBasis;
  pc.count = static_cast<uint32_t>(S);
  pc.cage_loops = static_cast<uint32_t>(cage.loops.size());
  pc.hole_count = static_cast<uint32_t>(cage.hole_count());
  pc.vertex_count = static_cast<uint32_t>(cage.vertex_count());
  pc.cage_at = 0;
  pc.holes_at = static_cast<uint32_t>(cage.vertex_count());
  const auto [gx, gy] = split_dispatch(context, (entries + kWorkgroupSize - 1) / kWorkgroupSize);
  context.submit_and_wait([&](VkCommandBuffer cmd) {
    pipeline_.bind(cmd, set_);
    pipeline_.push(cmd, &pc, sizeof(pc));
    vkCmdDispatch(cmd, gx, gy, 1);
  });
}

CertificateResult DenseCertifier::certify(const HarmonicMap& map, const CertificateOptions& options) {
  stats_ = {};
  const Context& ctx = *context_;
  const auto t_gpu = Clock::now();
  ctx.submit_and_wait([&](VkCommandBuffer cmd) { record(cmd, map, options); });
  const double upload_ms = stats_.upload_ms;
  stats_.gpu_ms = ms_since(t_gpu) - upload_ms;
  stats_.device_ms = pending_nonfinite_ ? 0.0 : ctx.last_device_ms();
  return collect();
}

void DenseCertifier::record(VkCommandBuffer cmd, const HarmonicMap& map, const CertificateOptions& options) {
  stats_.upload_ms = 0;
  pending_nonfinite_ = false;
  const auto t_upload = Clock::now();
  const int m = cage_.vertex_count(), N = cage_.hole_count();
  const Eigen::Index cols = m + N;
  if (map.phi.size() != cols || map.psi.size() != cols)
    throw InputError("dense certification: the map has " + std::to_string(map.phi.size()) + " φ and " +
                     std::to_string(map.psi.size()) + " ψ coefficients; the cage needs m + N = " + std::to_string(m) +
                     " + " + std::to_string(N) + " = " + std::to_string(cols));
  if (options.max_depth > kMaxDepth)
    throw InputError("dense certification: max_depth " + std::to_string(options.max_depth) +
                     " exceeds the GPU certifier's limit of " + std::to_string(kMaxDepth));
  if (!map.phi.allFinite() || !map.psi.allFinite()) {
    pending_nonfinite_ = true;  // collect() says so; nothing to run
    return;
  }

  // geom (complex entries): cage vertices, ρ, φ, ψ, then per column upper bounds of
  // (|S_j^φ|, |S_j^ψ|) (cage vertices) or (|φ_log|, |ψ_log|) (holes).
  std::vector<double> geom;
  geom.reserve(static_cast<size_t>(2 * (m + N + 7 * cols)));
  auto push = [&geom](double x, double y) {
    geom.push_back(x);
    geom.push_back(y);
  };
  PushConstants pc{};
  pc.cage_at = 0;
  for (const Loop& loop : cage_.loops)
    for (const cd& z : loop) push(z.real(), z.imag());
  pc.holes_at = static_cast<uint32_t>(geom.size() / 2);
  for (const cd& rho : cage_.hole_points) push(rho.real(), rho.imag());
  pc.phi_at = static_cast<uint32_t>(geom.size() / 2);
  for (Eigen::Index j = 0; j < cols; ++j) push(map.phi(j).real(), map.phi(j).imag());
  pc.psi_at = static_cast<uint32_t>(geom.size() / 2);
  for (Eigen::Index j = 0; j < cols; ++j) push(map.psi(j).real(), map.psi(j).imag());
  pc.jumps_at = static_cast<uint32_t>(geom.size() / 2);
  Eigen::VectorXd err_phi, err_psi;
  const Eigen::VectorXd s_phi = certificate_jumps(cage_, map.phi, &err_phi);
  const Eigen::VectorXd s_psi = certificate_jumps(cage_, map.psi, &err_psi);
  constexpr double u = std::numeric_limits<double>::epsilon() / 2;
  for (int j = 0; j < m; ++j) push((s_phi(j) + err_phi(j)) * (1 + 2 * u), (s_psi(j) + err_psi(j)) * (1 + 2 * u));
  for (int h = 0; h < N; ++h) push(std::abs(map.phi(m + h)) * (1 + 4 * u), std::abs(map.psi(m + h)) * (1 + 4 * u));
  if (basis_) {
    // The matrix's column inputs (certify.comp, basis_values): x = φ_{j+} − φ_j per
    // cage vertex (its loop's next vertex) and φ_{m+h} per hole, the same for ψ, then
    // upper bounds of |x| and of |φ_j|, |ψ_j|.
    pc.diff_at = static_cast<uint32_t>(geom.size() / 2);
    std::vector<cd> xa(static_cast<size_t>(cols)), xb(static_cast<size_t>(cols));
    int first = 0;
    for (const Loop& loop : cage_.loops) {
      const int k = static_cast<int>(loop.size());
      for (int j = 0; j < k; ++j) {
        const int v = first + j, vn = first + (j + 1 == k ? 0 : j + 1);
        xa[static_cast<size_t>(v)] = map.phi(vn) - map.phi(v);
        xb[static_cast<size_t>(v)] = map.psi(vn) - map.psi(v);
      }
      first += k;
    }
    for (int h = 0; h < N; ++h) {
      xa[static_cast<size_t>(m + h)] = map.phi(m + h);
      xb[static_cast<size_t>(m + h)] = map.psi(m + h);
    }
    for (const cd& x : xa) push(x.real(), x.imag());
    for (const cd& x : xb) push(x.real(), x.imag());
    for (size_t j = 0; j < xa.size(); ++j) push(std::abs(xa[j]) * (1 + 4 * u), std::abs(xb[j]) * (1 + 4 * u));
    for (Eigen::Index j = 0; j < cols; ++j)
      push(std::abs(map.phi(j)) * (1 + 4 * u), std::abs(map.psi(j)) * (1 + 4 * u));
  }

  const Context& ctx = *context_;
  const VkDeviceSize geom_bytes = geom.size() * sizeof(double);
  if (!geom_ || geom_.size() < geom_bytes) {
    geom_ = Buffer(ctx, std::max<VkDeviceSize>(geom_bytes, 64), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    set_.bind(kGeom, geom_);
  }
  geom_.write(geom.data(), geom_bytes);

  const uint32_t S = static_cast<uint32_t>(segments_.size());
  pc.count = S;
  pc.cage_loops = static_cast<uint32_t>(cage_.loops.size());
  pc.hole_count = static_cast<uint32_t>(N);
  pc.vertex_count = static_cast<uint32_t>(m);
  pc.max_depth = static_cast<uint32_t>(std::max(options.max_depth, 0));
  pc.max_pieces = static_cast<uint32_t>(
      std::clamp<long>(options.max_pieces_per_segment, 0, static_cast<long>(std::numeric_limits<uint32_t>::max())));
  pc.flags = (options.stop_at_first_failure ? kStopAtFirstFailure : 0u) | (basis_ ? kHaveLip : 0u);
  stats_.upload_ms = ms_since(t_upload);

  const auto [gx, gy] = split_dispatch(ctx, (S + kWorkgroupSize - 1) / kWorkgroupSize);
  const auto [vx, vy] = split_dispatch(ctx, (S + kRowsPerGroup - 1) / kRowsPerGroup);
  {
    // Earlier submissions' shader writes and reads of these buffers come first.
    memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                   VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                   VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    vkCmdFillBuffer(cmd, control_.handle(), 0, VK_WHOLE_SIZE, 0u);
    memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    pipeline_.bind(cmd, set_);
    PushConstants p = pc;
    p.mode = basis_ ? kModeBasisValues : kModeValues;
    pipeline_.push(cmd, &p, sizeof(p));
    if (basis_)
      vkCmdDispatch(cmd, vx, vy, 1);
    else
      vkCmdDispatch(cmd, gx, gy, 1);
    memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                   VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    p.mode = kModeSegments;
    pipeline_.push(cmd, &p, sizeof(p));
    vkCmdDispatch(cmd, gx, gy, 1);
    if (readback_) {
      memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                     VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
      const VkBufferCopy region{0, 0, static_cast<VkDeviceSize>(S) * sizeof(SegmentOut)};
      vkCmdCopyBuffer(cmd, out_.handle(), readback_.handle(), 1, &region);
      memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                     VK_ACCESS_HOST_READ_BIT);
    } else {
      memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                     VK_ACCESS_HOST_READ_BIT);
    }
  }
}

CertificateResult DenseCertifier::collect() {
  if (pending_nonfinite_) {
    pending_nonfinite_ = false;
    CertificateResult r;
    r.reason = "the map's coefficients are not finite";
    return r;
  }
  const uint32_t S = static_cast<uint32_t>(segments_.size());
  const auto t_read = Clock::now();
  std::vector<SegmentOut> raw(S);
  (readback_ ? readback_ : out_).read(raw.data(), raw.size() * sizeof(SegmentOut));
  outcomes_.assign(S, SegmentCertificate{});
  status_.assign(S, SegmentStatus::kCertified);
  std::vector<double> abs_a(S), abs_b(S);
  for (uint32_t i = 0; i < S; ++i) {
    const SegmentOut& o = raw[i];
    if (o.status > static_cast<uint32_t>(SegmentStatus::kStopped))
      throw VulkanError("dense certification: the shader reported an unknown status " + std::to_string(o.status) +
                        " for segment " + std::to_string(i));
    const auto status = static_cast<SegmentStatus>(o.status);
    SegmentCertificate& c = outcomes_[i];
    c.ok = status == SegmentStatus::kCertified || status == SegmentStatus::kSkipped;
    c.arg = o.arg;
    c.margin = o.margin;
    c.sigma1 = o.sigma1;
    c.sigma2 = o.sigma2;
    c.k = o.k;
    c.pieces = static_cast<long>(o.pieces);
    c.fail_point = cd(o.fail_x, o.fail_y);
    status_[i] = status;
    abs_a[i] = o.abs_a;
    abs_b[i] = o.abs_b;
  }
  CertificateResult r = reduce_certificate(segments_, outcomes_, abs_a, abs_b);
  stats_.readback_ms = ms_since(t_read);
  return r;
}

}  // namespace hsi::compute
