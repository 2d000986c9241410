// Host side of the dense evaluation pass (see dense_eval.h and shaders/dense_eval.comp):
// packs the cage, coefficients and optional mask shape into two small buffers, then
// evaluates the points in passes of bounded size and reads the fields back.
#include "hsi/compute/dense_eval.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "hsi/compute/spirv/dense_eval_f32.h"
#include "hsi/compute/spirv/dense_eval_f64.h"
#include "timing.h"

namespace hsi::compute {

namespace {

// Mirrors `Push` in dense_eval.comp.
struct PushConstants {
  uint32_t base, count, flags, width;
  uint32_t cage_loops, shape_loops, hole_count, cage_at;
  uint32_t holes_at, phi_at, psi_at, vertex_count;
  uint32_t inva_at;
};
static_assert(sizeof(PushConstants) == 52);
constexpr uint32_t kGridMode = 1u, kMask = 2u, kSkipOutside = 4u, kRowPass = 8u, kRowMask = 16u;
constexpr uint32_t kRowCap = 64;         // crossings stored per grid row (kRowCap in the shader)
constexpr uint32_t kMaxRowMaskLoops = 32;  // the row mask keeps one parity bit per loop
constexpr uint32_t kWorkgroupSize = 64;  // local_size_x in the shader

constexpr std::array<VkDescriptorType, 10> kBindings = {
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
constexpr uint32_t kOutBinding = 3;  // out_[k] is binding 3 + k
constexpr uint32_t kRowCountBinding = 8, kRowCrossBinding = 9;

uint32_t to_u32(size_t n, const char* what) {
  if (n > std::numeric_limits<uint32_t>::max())
    throw InputError(std::string("dense evaluation: too many ") + what + " (" + std::to_string(n) + ")");
  return static_cast<uint32_t>(n);
}

// Writes doubles as the shader's Real (double or float) into an upload buffer,
// (re)creating it when too small.
void upload_reals(const Context& ctx, Buffer& buffer, const std::vector<double>& values, bool as_double) {
  const VkDeviceSize bytes = values.size() * (as_double ? sizeof(double) : sizeof(float));
  if (!buffer || buffer.size() < bytes)
    buffer = Buffer(ctx, std::max<VkDeviceSize>(bytes, 64), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
  if (as_double) {
    buffer.write(values.data(), bytes);
  } else {
    std::vector<float> f(values.begin(), values.end());
    buffer.write(f.data(), bytes);
  }
}

}  // namespace

// --- grid ---------------------------------------------------------------------------

std::vector<cd> Grid::points() const {
  std::vector<cd> out;
  out.reserve(size());
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) out.push_back(point(i, j));
  return out;
}

Grid Grid::covering(const BoundingBox& box, int width, int height) {
  if (width <= 0 || height <= 0)
    throw InputError("Grid::covering: the grid needs a positive size, got " + std::to_string(width) + " x " +
                     std::to_string(height));
  const cd ext = box.hi - box.lo;
  Grid g;
  g.spacing = {ext.real() / width, ext.imag() / height};
  g.origin = box.lo + 0.5 * g.spacing;
  g.width = width;
  g.height = height;
  return g;
}

Grid Grid::covering(const BoundingBox& box, int max_side) {
  if (max_side <= 0) throw InputError("Grid::covering: max_side must be positive, got " + std::to_string(max_side));
  const cd ext = box.hi - box.lo;
  const double cell = std::max(ext.real(), ext.imag()) / max_side;
  Grid g;
  g.width = std::max(1, static_cast<int>(std::lround(ext.real() / cell)));
  g.height = std::max(1, static_cast<int>(std::lround(ext.imag() / cell)));
  g.spacing = {cell, cell};
  const cd centre = 0.5 * (box.lo + box.hi);
  g.origin = centre - cd(0.5 * (g.width - 1) * cell, 0.5 * (g.height - 1) * cell);
  return g;
}

// --- evaluator ------------------------------------------------------------------------

struct DenseEvaluator::Job {
  const Cage& cage;
  const HarmonicMap& map;
  std::span<const cd> points;  // point mode
  const Grid* grid = nullptr;  // grid mode
  const Shape* shape = nullptr;
  VkCommandBuffer record_into = VK_NULL_HANDLE;  // record_points: record one pass here, no readback
};

DenseEvaluator::DenseEvaluator(const Context& context, const DenseEvalOptions& options)
    : context_(&context), options_(options) {
  const bool has64 = context.info().float64;
  switch (options.precision) {
    case Precision::kAuto: double_ = has64; break;
    case Precision::kFloat: double_ = false; break;
    case Precision::kDouble:
      if (!has64)
        throw VulkanError("dense evaluation: double precision was requested but " + context.info().name +
                          " has no shaderFloat64");
      double_ = true;
      break;
  }
  const std::span<const uint32_t> spirv =
      double_ ? std::span<const uint32_t>(dense_eval_f64) : std::span<const uint32_t>(dense_eval_f32);
  pipeline_ = ComputePipeline(context, spirv, kBindings, sizeof(PushConstants));
  set_ = DescriptorSet(context, pipeline_.layout());
}

DenseField DenseEvaluator::evaluate_points(const Cage& cage, const HarmonicMap& map, std::span<const cd> points) {
  return run(Job{cage, map, points, nullptr, nullptr});
}

void DenseEvaluator::record_points(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map,
                                   std::span<const cd> points) {
  Job job{cage, map, points, nullptr, nullptr};
  job.record_into = cmd;
  run(job);
}

namespace {
void check_grid(const Grid& grid) {
  if (grid.width < 0 || grid.height < 0)
    throw InputError("dense evaluation: negative grid size " + std::to_string(grid.width) + " x " +
                     std::to_string(grid.height));
  if (!(std::isfinite(grid.origin.real()) && std::isfinite(grid.origin.imag()) && grid.spacing.real() > 0 &&
        grid.spacing.imag() > 0 && std::isfinite(grid.spacing.real()) && std::isfinite(grid.spacing.imag())))
    throw InputError("dense evaluation: the grid needs a finite origin and finite positive spacing");
}
}  // namespace

DenseField DenseEvaluator::evaluate_grid(const Cage& cage, const HarmonicMap& map, const Grid& grid,
                                         const Shape* mask_shape) {
  check_grid(grid);
  return run(Job{cage, map, {}, &grid, mask_shape});
}

void DenseEvaluator::record_grid(VkCommandBuffer cmd, const Cage& cage, const HarmonicMap& map, const Grid& grid,
                                 const Shape* mask_shape) {
  check_grid(grid);
  Job job{cage, map, {}, &grid, mask_shape};
  job.record_into = cmd;
  run(job);
}

void DenseEvaluator::ensure_capacity(uint32_t points) {
  if (points <= capacity_) return;
  const VkDeviceSize real = double_ ? 8 : 4;
  const VkDeviceSize elem[5] = {2 * real, 2 * real, 2 * real, 4 * real, 4};
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  points_ = Buffer(*context_, points * 2 * real, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
  for (int k = 0; k < 5; ++k) {
    out_[k] = Buffer(*context_, points * elem[k], usage, MemoryUse::kDeviceLocal);
    // Read results in place only from cached host-visible memory (CPU devices,
    // integrated GPUs); uncached BAR memory is slow to read, so stage it.
    const bool direct = out_[k].host_visible() && (out_[k].memory_flags() & VK_MEMORY_PROPERTY_HOST_CACHED_BIT) &&
                        !options_.force_staging;
    readback_[k] = direct ? Buffer() : Buffer(*context_, points * elem[k], VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                              MemoryUse::kReadback);
  }
  capacity_ = points;
}

DenseField DenseEvaluator::run(const Job& job) {
  const Cage& cage = job.cage;
  const auto t_upload = Clock::now();
  stats_ = {};

  // --- check the inputs -------------------------------------------------------------
  const int m = cage.vertex_count(), N = cage.hole_count();
  if (cage.loops.empty() || m == 0) throw InputError("dense evaluation: the cage has no vertices");
  for (size_t l = 0; l < cage.loops.size(); ++l)
    if (cage.loops[l].size() < 2)
      throw InputError("dense evaluation: cage " + loop_name(static_cast<int>(l)) + " has " +
                       std::to_string(cage.loops[l].size()) + " vertices; a cage loop needs at least 2");
  const Eigen::Index cols = m + N;
  if (job.map.phi.size() != cols || job.map.psi.size() != cols)
    throw InputError("dense evaluation: the map has " + std::to_string(job.map.phi.size()) + " φ and " +
                     std::to_string(job.map.psi.size()) + " ψ coefficients but the cage needs m + N = " +
                     std::to_string(m) + " + " + std::to_string(N) + " = " + std::to_string(cols) + " of each");
  const size_t total = job.grid ? job.grid->size() : job.points.size();
  to_u32(total, "points");

  DenseField out;
  out.double_precision = double_;
  if (job.grid) {
    out.width = job.grid->width;
    out.height = job.grid->height;
  }
  const bool mask = job.shape != nullptr;
  if (!job.record_into) {  // record_points leaves the results on the device
    out.f.resize(total);
    out.f_z.resize(total);
    out.fzbar_conj.resize(total);
    out.sigma1.resize(total);
    out.sigma2.resize(total);
    out.distortion.resize(total);
    out.dirichlet.resize(total);
    out.det_sign.resize(total);
    if (mask) out.inside.resize(total);
  }
  if (total == 0) return out;

  // --- pack the cage, coefficients and mask shape --------------------------------------
  // geom (complex entries): origin, spacing, cage vertices, ρ, φ, ψ, shape vertices.
  std::vector<double> geom;
  std::vector<uint32_t> loops;
  auto push = [&geom](cd z) {
    geom.push_back(z.real());
    geom.push_back(z.imag());
  };
  push(job.grid ? job.grid->origin : cd(0));
  push(job.grid ? job.grid->spacing : cd(0));
  PushConstants pc{};
  pc.cage_at = 2;
  for (const Loop& loop : cage.loops) {
    loops.push_back(static_cast<uint32_t>(geom.size() / 2 - pc.cage_at));
    loops.push_back(static_cast<uint32_t>(loop.size()));
    for (const cd& z : loop) push(z);
  }
  pc.holes_at = static_cast<uint32_t>(geom.size() / 2);
  for (const cd& rho : cage.hole_points) push(rho);
  pc.phi_at = static_cast<uint32_t>(geom.size() / 2);
  for (Eigen::Index j = 0; j < cols; ++j) push(job.map.phi(j));
  pc.psi_at = static_cast<uint32_t>(geom.size() / 2);
  for (Eigen::Index j = 0; j < cols; ++j) push(job.map.psi(j));
  pc.inva_at = static_cast<uint32_t>(geom.size() / 2);
  for (const Loop& loop : cage.loops)
    for (size_t j = 0; j < loop.size(); ++j) push(1.0 / (loop[j + 1 == loop.size() ? 0 : j + 1] - loop[j]));
  if (mask)
    for (int l = 0; l < job.shape->loop_count(); ++l) {
      const Loop& loop = job.shape->loop(l);
      if (loop.size() < 3)
        throw InputError("dense evaluation: mask shape " + loop_name(l) + " has fewer than 3 vertices");
      loops.push_back(static_cast<uint32_t>(geom.size() / 2));
      loops.push_back(static_cast<uint32_t>(loop.size()));
      for (const cd& z : loop) push(z);
    }
  pc.cage_loops = static_cast<uint32_t>(cage.loops.size());
  pc.shape_loops = mask ? static_cast<uint32_t>(job.shape->loop_count()) : 0u;
  pc.hole_count = static_cast<uint32_t>(N);
  pc.vertex_count = static_cast<uint32_t>(m);
  pc.width = job.grid ? static_cast<uint32_t>(job.grid->width) : 0u;
  pc.flags = (job.grid ? kGridMode : 0u) | (mask ? kMask : 0u) | (mask && options_.skip_outside ? kSkipOutside : 0u);
  // A grid's mask from each row's crossings with the shape (a pass over the rows
  // first): far fewer tests per point than every edge of the shape.
  const bool row_mask = job.grid && mask && pc.shape_loops <= kMaxRowMaskLoops && job.grid->height > 0;
  if (row_mask) pc.flags |= kRowMask;

  const Context& ctx = *context_;
  {
    const VkDeviceSize bytes = loops.size() * sizeof(uint32_t);
    if (!loops_ || loops_.size() < bytes)
      loops_ = Buffer(ctx, std::max<VkDeviceSize>(bytes, 64), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kUpload);
    loops_.write(loops.data(), bytes);
  }
  upload_reals(ctx, geom_, geom, double_);

  // --- passes -----------------------------------------------------------------------
  const size_t real = double_ ? sizeof(double) : sizeof(float);
  const uint64_t range_limit = ctx.info().max_storage_buffer_range / (4 * real);
  const uint32_t pass_max = static_cast<uint32_t>(std::max<uint64_t>(
      kWorkgroupSize, std::min<uint64_t>({options_.max_points_per_pass, range_limit, total})));
  ensure_capacity(pass_max);
  const uint32_t rows = row_mask ? static_cast<uint32_t>(job.grid->height) : 1u;
  if (!row_count_ || row_count_.size() < rows * sizeof(uint32_t)) {
    row_count_ = Buffer(ctx, rows * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::kDeviceLocal);
    row_cross_ = Buffer(ctx, static_cast<VkDeviceSize>(rows) * kRowCap * 2 * real, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                        MemoryUse::kDeviceLocal);
  }
  set_.bind(0, loops_);
  set_.bind(1, geom_);
  set_.bind(2, points_);
  for (uint32_t k = 0; k < 5; ++k) set_.bind(kOutBinding + k, out_[k]);
  set_.bind(kRowCountBinding, row_count_);
  set_.bind(kRowCrossBinding, row_cross_);
  stats_.upload_ms += ms_since(t_upload);

  // first: also the row pass (the rows serve every pass of the grid).
  auto record_dispatch = [&](VkCommandBuffer cmd, uint32_t n, bool first) {
    pipeline_.bind(cmd, set_);
    if (row_mask && first) {
      PushConstants rp = pc;
      rp.flags |= kRowPass;
      rp.count = rows;
      pipeline_.push(cmd, &rp, sizeof(rp));
      const auto [rx, ry] = split_dispatch(ctx, (rows + kWorkgroupSize - 1) / kWorkgroupSize);
      vkCmdDispatch(cmd, rx, ry, 1);
      memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                     VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT);
    }
    const auto [gx, gy] = split_dispatch(ctx, (n + kWorkgroupSize - 1) / kWorkgroupSize);
    pipeline_.push(cmd, &pc, sizeof(pc));
    vkCmdDispatch(cmd, gx, gy, 1);
  };
  if (job.record_into) {
    if (total > pass_max)
      throw InputError("dense evaluation: " + std::to_string(total) + " points do not fit one pass (at most " +
                       std::to_string(pass_max) + " on this device with these options)");
    if (!job.grid) {
      std::vector<double> all;
      all.reserve(2 * total);
      for (const cd& p : job.points) {
        all.push_back(p.real());
        all.push_back(p.imag());
      }
      upload_reals(ctx, points_, all, double_);
    }
    pc.base = 0;
    pc.count = static_cast<uint32_t>(total);
    record_dispatch(job.record_into, pc.count, true);
    return out;
  }

  std::vector<double> chunk;
  std::vector<float> chunk_f;
  std::vector<uint32_t> flags;
  for (size_t start = 0; start < total; start += pass_max) {
    const uint32_t n = static_cast<uint32_t>(std::min<size_t>(pass_max, total - start));
    pc.base = static_cast<uint32_t>(start);
    pc.count = n;
    if (!job.grid) {
      const auto t0 = Clock::now();
      chunk.clear();
      for (size_t i = start; i < start + n; ++i) {
        chunk.push_back(job.points[i].real());
        chunk.push_back(job.points[i].imag());
      }
      upload_reals(ctx, points_, chunk, double_);
      stats_.upload_ms += ms_since(t0);
    }

    const auto t_gpu = Clock::now();
    const bool staged = static_cast<bool>(readback_[0]) || static_cast<bool>(readback_[4]);
    ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      record_dispatch(cmd, n, start == 0);
      if (staged) {
        memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                       VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
        const VkDeviceSize elem[5] = {2 * real, 2 * real, 2 * real, 4 * real, 4};
        for (int k = 0; k < 5; ++k)
          if (readback_[k]) {
            const VkBufferCopy region{0, 0, n * elem[k]};
            vkCmdCopyBuffer(cmd, out_[k].handle(), readback_[k].handle(), 1, &region);
          }
        memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                       VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                       VK_ACCESS_HOST_READ_BIT);
      } else {
        memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                       VK_ACCESS_HOST_READ_BIT);
      }
    });
    stats_.gpu_ms += ms_since(t_gpu);
    const double device = ctx.last_device_ms();
    stats_.device_ms = device < 0 || stats_.device_ms < 0 ? -1.0 : stats_.device_ms + device;
    ++stats_.passes;

    // --- read back ------------------------------------------------------------------
    const auto t_read = Clock::now();
    auto source = [&](int k) -> const Buffer& { return readback_[k] ? readback_[k] : out_[k]; };
    // Reads n × width reals of buffer k as doubles into `chunk`.
    auto read_reals = [&](int k, size_t width) {
      chunk.resize(n * width);
      if (double_) {
        source(k).read(chunk.data(), n * width * sizeof(double));
      } else {
        chunk_f.resize(n * width);
        source(k).read(chunk_f.data(), n * width * sizeof(float));
        std::copy(chunk_f.begin(), chunk_f.end(), chunk.begin());
      }
    };
    std::vector<cd>* complex_out[3] = {&out.f, &out.f_z, &out.fzbar_conj};
    for (int k = 0; k < 3; ++k) {
      read_reals(k, 2);
      for (uint32_t i = 0; i < n; ++i) (*complex_out[k])[start + i] = cd(chunk[2 * i], chunk[2 * i + 1]);
    }
    read_reals(3, 4);
    for (uint32_t i = 0; i < n; ++i) {
      out.sigma1[start + i] = chunk[4 * i];
      out.sigma2[start + i] = chunk[4 * i + 1];
      out.distortion[start + i] = chunk[4 * i + 2];
      out.dirichlet[start + i] = chunk[4 * i + 3];
    }
    flags.resize(n);
    source(4).read(flags.data(), n * sizeof(uint32_t));
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t fl = flags[i];
      out.det_sign[start + i] = (fl & kFlagDetPositive) ? int8_t{1} : (fl & kFlagDetNegative) ? int8_t{-1} : int8_t{0};
      if (mask) out.inside[start + i] = (fl & kFlagInside) ? 1 : 0;
    }
    stats_.readback_ms += ms_since(t_read);
  }
  return out;
}

}  // namespace hsi::compute
