// The C API (hsi/hsi.h) over the C++ engine: handles, status codes and messages;
// every entry point catches everything, so no exception crosses into C.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <thread>

#include "built.h"
#include "c_api_internal.h"
#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/batch.h"
#include "hsi/keyframes.h"
#include "hsi/runtime/backend.h"

using namespace hsi;
using hsi::capi::ApiError;

namespace {

thread_local std::string g_error;
std::atomic<long> g_live_handles{0};

void* default_allocate(size_t size, size_t alignment, void*) {
  alignment = std::max(alignment, alignof(std::max_align_t));
  return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
void default_release(void* p, void*) { std::free(p); }
hsi_allocator g_alloc{default_allocate, default_release, nullptr};

void* baked_allocate(size_t bytes, void*) { return g_alloc.allocate(bytes, 16, g_alloc.user); }
void baked_release(void* p, void*) { g_alloc.release(p, g_alloc.user); }

template <class T>
T* new_handle() {
  void* p = g_alloc.allocate(sizeof(T), alignof(T), g_alloc.user);
  if (!p) throw std::bad_alloc();
  try {
    T* h = new (p) T();
    ++g_live_handles;
    return h;
  } catch (...) {
    g_alloc.release(p, g_alloc.user);
    throw;
  }
}

template <class T>
void delete_handle(T* h) {
  if (!h) return;
  h->~T();
  g_alloc.release(h, g_alloc.user);
  --g_live_handles;
}

hsi_status set_error(hsi_status s, const std::string& message) {
  g_error = message;
  return s;
}

[[noreturn]] void fail(hsi_status s, const std::string& message) { throw ApiError{s, message}; }

void require(bool ok, const char* function, const char* what) {
  if (!ok) fail(HSI_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + what);
}

template <class F>
hsi_status guard(F&& body) noexcept {
  g_error.clear();
  try {
    body();
    return HSI_OK;
  } catch (const ApiError& e) {
    return set_error(e.status, e.message);
  } catch (const InputError& e) {
    return set_error(HSI_ERROR_INPUT, e.what());
  } catch (const std::bad_alloc&) {
    return set_error(HSI_ERROR_OUT_OF_MEMORY, "out of memory");
  } catch (const std::filesystem::filesystem_error& e) {
    return set_error(HSI_ERROR_IO, e.what());
  } catch (const std::exception& e) {
    return set_error(HSI_ERROR_INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return set_error(HSI_ERROR_INTERNAL, "internal error: unknown exception");
  }
}

// Buffer protocol: *length = bytes needed (without a NUL); copy with a NUL when it fits.
void copy_out(const std::string& text, char* buffer, size_t capacity, size_t* length, bool nul) {
  if (length) *length = text.size();
  const size_t need = text.size() + (nul ? 1 : 0);
  if (!buffer || capacity < need)
    fail(HSI_ERROR_BUFFER_TOO_SMALL,
         "the buffer holds " + std::to_string(buffer ? capacity : 0) + " bytes; " + std::to_string(need) + " are needed");
  std::memcpy(buffer, text.data(), text.size());
  if (nul) buffer[text.size()] = '\0';
}

const ShapeSetup& ensure_setup(hsi_scene* s) {
  if (!s->setup) s->setup = scene_setup(s->scene, s->samples, s->hessian_ratio);
  return *s->setup;
}

std::vector<cd> read_points(const double* xy, size_t count) {
  std::vector<cd> p(count);
  for (size_t i = 0; i < count; ++i) p[i] = cd(xy[2 * i], xy[2 * i + 1]);
  return p;
}

// A Distortion into the report's four fields of one kind (sampled, an envelope, certified).
void put(const Distortion& d, double& sigma1_max, double& sigma2_min, double& conformal_max, double& isometric_max) {
  sigma1_max = d.sigma1_max;
  sigma2_min = d.sigma2_min;
  conformal_max = d.conformal_max;
  isometric_max = d.isometric_max;
}

hsi_frame_report to_report(const FrameResult& f) {
  hsi_frame_report r{};
  r.t = f.t;
  r.keyframe = f.keyframe;
  r.certified = f.certified;
  r.converged = f.converged;
  r.stop = static_cast<int>(f.stop);
  r.iterations = f.iterations;
  r.energy = f.energy;
  r.ms = f.ms;
  put(f.distortion, r.sigma1_max, r.sigma2_min, r.conformal_max, r.isometric_max);
  put(f.bound, r.bound_sigma1_max, r.bound_sigma2_min, r.bound_conformal_max, r.bound_isometric_max);
  r.bound_excess = f.bound_excess;
  r.overlaps = f.overlap.overlaps();
  r.crossings = f.overlap.crossings;
  r.held = f.held;
  // distortion_certified and certified_bound_excess are NaN for an uncertified frame.
  put(f.distortion_certified, r.certified_sigma1_max, r.certified_sigma2_min, r.certified_conformal_max,
      r.certified_isometric_max);
  put(f.certified_bound, r.certified_bound_sigma1_max, r.certified_bound_sigma2_min, r.certified_bound_conformal_max,
      r.certified_bound_isometric_max);
  r.certified_bound_excess = f.certified_bound_excess;
  return r;
}

const FrameResult& frame_of(const hsi_sequence* s, uint32_t frame, const char* function) {
  require(s, function, "sequence is NULL");
  if (frame >= s->seq.frames.size())
    fail(HSI_ERROR_OUT_OF_RANGE, std::string(function) + ": frame " + std::to_string(frame) + " is past the end (" +
                                     std::to_string(s->seq.frames.size()) + " frames)");
  return s->seq.frames[frame];
}

// Points must lie in the cage domain, where the basis is defined (not on the cage).
void check_in_cage(const Cage& cage, double size, const std::vector<cd>& points) {
  const double eps = 1e-9 * size;
  for (size_t i = 0; i < points.size(); ++i) {
    const cd p = points[i];
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) fail(HSI_ERROR_INPUT, "point " + std::to_string(i) + " is not finite");
    for (size_t l = 0; l < cage.loops.size(); ++l) {
      const bool inside = point_in_loop(cage.loops[l], p);
      if ((l == 0) != inside || loop_distance(cage.loops[l], p) <= eps)
        fail(HSI_ERROR_INPUT, "point " + std::to_string(i) + " at (" + std::to_string(p.real()) + ", " + std::to_string(p.imag()) +
                                  ") lies " + (l == 0 ? "outside (or on) the cage's outer loop" : "inside (or on) the cage loop of hole " + std::to_string(l)) +
                                  ": maps are defined inside the cage only (the shape and a margin around it)");
    }
  }
}

}  // namespace

// hsi_stop mirrors NewtonStop value for value.
static_assert(HSI_STOP_COUNT == kNewtonStopCount);
static_assert(HSI_STOP_CONVERGED == static_cast<int>(NewtonStop::Converged));
static_assert(HSI_STOP_ITERATION_LIMIT == static_cast<int>(NewtonStop::IterationLimit));
static_assert(HSI_STOP_STAGNATED == static_cast<int>(NewtonStop::Stagnated));
static_assert(HSI_STOP_CERTIFICATE_REFUSED == static_cast<int>(NewtonStop::CertificateRefused));
static_assert(HSI_STOP_NO_DECREASE == static_cast<int>(NewtonStop::NoDecrease));
static_assert(HSI_STOP_NOT_FACTORED == static_cast<int>(NewtonStop::NotFactored));
static_assert(HSI_STOP_START_FOLDS == static_cast<int>(NewtonStop::StartFolds));
static_assert(HSI_STOP_START_NOT_CERTIFIED == static_cast<int>(NewtonStop::StartNotCertified));

extern "C" {

uint32_t hsi_version(void) { return HSI_VERSION; }
const char* hsi_version_string(void) { return HSI_VERSION_STRING; }

const char* hsi_status_name(hsi_status s) {
  switch (s) {
    case HSI_OK: return "ok";
    case HSI_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case HSI_ERROR_INPUT: return "input refused";
    case HSI_ERROR_IO: return "I/O error";
    case HSI_ERROR_NOT_CERTIFIED: return "not certified";
    case HSI_ERROR_OUT_OF_RANGE: return "out of range";
    case HSI_ERROR_UNSUPPORTED: return "unsupported";
    case HSI_ERROR_OUT_OF_MEMORY: return "out of memory";
    case HSI_ERROR_BUFFER_TOO_SMALL: return "buffer too small";
    case HSI_ERROR_CANCELLED: return "cancelled";
    case HSI_ERROR_INTERNAL: return "internal error";
  }
  return "unknown status";
}

const char* hsi_stop_name(int stop) {
  if (stop < 0 || stop >= HSI_STOP_COUNT) return "unknown";
  return to_string(static_cast<NewtonStop>(stop));
}

const char* hsi_last_error(void) { return g_error.c_str(); }

hsi_status hsi_set_allocator(const hsi_allocator* allocator) {
  return guard([&] {
    if (g_live_handles.load() != 0)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_set_allocator: " + std::to_string(g_live_handles.load()) + " handle(s) still exist");
    if (allocator && (!allocator->allocate || !allocator->release))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_set_allocator: allocate and release must both be given");
    if (allocator) {
      g_alloc = *allocator;
      const hsib_allocator b{baked_allocate, baked_release, nullptr};
      hsib_set_allocator(&b);
    } else {
      g_alloc = {default_allocate, default_release, nullptr};
      hsib_set_allocator(nullptr);
    }
  });
}

// ---------------------------------------------------------------- scenes

hsi_status hsi_scene_load_file(const char* path, hsi_scene** out) {
  if (out) *out = nullptr;
  return guard([&] {
    require(path && out, "hsi_scene_load_file", "path or out is NULL");
    if (!std::filesystem::exists(path)) fail(HSI_ERROR_IO, std::string(path) + ": no such file");
    Scene scene = load_scene(path);
    hsi_scene* s = new_handle<hsi_scene>();
    s->scene = std::move(scene);
    *out = s;
  });
}

hsi_status hsi_scene_load_memory(const char* json, size_t size, const char* base_dir, hsi_scene** out) {
  if (out) *out = nullptr;
  return guard([&] {
    require(json && out, "hsi_scene_load_memory", "json or out is NULL");
    Scene scene = parse_scene(std::string(json, size), base_dir ? base_dir : std::filesystem::current_path().string(), "scene (memory)");
    hsi_scene* s = new_handle<hsi_scene>();
    s->scene = std::move(scene);
    *out = s;
  });
}

void hsi_scene_destroy(hsi_scene* scene) { delete_handle(scene); }

hsi_status hsi_scene_get_info(hsi_scene* s, hsi_scene_info* info) {
  return guard([&] {
    require(s && info, "hsi_scene_get_info", "scene or info is NULL");
    if (!s->scene.cage) s->scene.cage = build_cage(s->scene.shape, s->scene.cage_options);
    hsi_scene_info r{};
    r.loop_count = static_cast<uint32_t>(s->scene.shape.loop_count());
    r.hole_count = static_cast<uint32_t>(s->scene.shape.holes.size());
    r.cage_vertex_count = static_cast<uint32_t>(s->scene.cage->vertex_count());
    r.coefficient_count = static_cast<uint32_t>(basis_size(*s->scene.cage));
    r.handle_count = static_cast<uint32_t>(s->scene.handles.size());
    r.keyframe_count = static_cast<uint32_t>(s->scene.keyframes.size());
    r.samples = static_cast<uint32_t>(s->samples > 0 ? s->samples : s->scene.samples);
    r.hessian_ratio = s->hessian_ratio > 0 ? s->hessian_ratio : s->scene.hessian_ratio;
    const BoundingBox bb = bounding_box(s->scene.shape);
    r.bbox[0] = bb.lo.real();
    r.bbox[1] = bb.lo.imag();
    r.bbox[2] = bb.hi.real();
    r.bbox[3] = bb.hi.imag();
    r.size = bb.diagonal();
    r.has_texture = !s->scene.texture.empty();
    *info = r;
  });
}

hsi_status hsi_scene_set_sampling(hsi_scene* s, uint32_t samples, double ratio) {
  return guard([&] {
    require(s, "hsi_scene_set_sampling", "scene is NULL");
    if (samples != 0 && (samples < 100 || samples > 10000000))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_scene_set_sampling: samples must be 0 (the scene's) or in [100, 1e7], got " + std::to_string(samples));
    if (!(ratio == 0 || (ratio > 0 && ratio <= 1)))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_scene_set_sampling: the Hessian ratio must be 0 (the scene's) or in (0, 1]");
    s->samples = static_cast<int>(samples);
    s->hessian_ratio = ratio;
    s->setup.reset();  // interpolators and sequences keep their own
  });
}

hsi_status hsi_scene_set_handles(hsi_scene* s, const double* xy, uint32_t count) {
  return guard([&] {
    require(s && (xy || count == 0), "hsi_scene_set_handles", "scene or xy is NULL");
    std::vector<cd> handles = read_points(xy, count);
    for (size_t i = 0; i < handles.size(); ++i)
      if (!point_in_shape(s->scene.shape, handles[i]))
        fail(HSI_ERROR_INPUT, "handle " + std::to_string(i) + " at (" + std::to_string(handles[i].real()) + ", " +
                                  std::to_string(handles[i].imag()) + ") is not inside the shape");
    s->scene.handles = std::move(handles);
    auto& ks = s->scene.keyframes;
    for (auto it = ks.begin(); it != ks.end();) {
      if (it->targets.size() != count) {
        if (!it->coefficients) {
          it = ks.erase(it);
          continue;
        }
        it->targets.clear();
      }
      ++it;
    }
  });
}

hsi_status hsi_scene_get_handles(hsi_scene* s, double* xy, uint32_t capacity, uint32_t* count) {
  return guard([&] {
    require(s && (xy || capacity == 0), "hsi_scene_get_handles", "scene or xy is NULL");
    const auto& h = s->scene.handles;
    if (count) *count = static_cast<uint32_t>(h.size());
    for (size_t i = 0; i < h.size() && i < capacity; ++i) {
      xy[2 * i] = h[i].real();
      xy[2 * i + 1] = h[i].imag();
    }
  });
}

hsi_status hsi_scene_clear_keyframes(hsi_scene* s) {
  return guard([&] {
    require(s, "hsi_scene_clear_keyframes", "scene is NULL");
    s->scene.keyframes.clear();
  });
}

hsi_status hsi_scene_add_keyframe(hsi_scene* s, double time, const double* targets_xy, uint32_t count, hsi_keyframe_report* report) {
  return guard([&] {
    require(s && (targets_xy || count == 0), "hsi_scene_add_keyframe", "scene or targets are NULL");
    if (!std::isfinite(time)) fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_scene_add_keyframe: time is not finite");
    if (count != s->scene.handles.size())
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_scene_add_keyframe: " + std::to_string(count) + " targets for " +
                                           std::to_string(s->scene.handles.size()) + " handles");
    if (!s->scene.keyframes.empty() && !(time > s->scene.keyframes.back().time))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_scene_add_keyframe: time " + std::to_string(time) + " must exceed the last keyframe's (" +
                                           std::to_string(s->scene.keyframes.back().time) + ")");
    const std::vector<cd> targets = read_points(targets_xy, count);
    for (size_t i = 0; i < targets.size(); ++i)
      if (!std::isfinite(targets[i].real()) || !std::isfinite(targets[i].imag()))
        fail(HSI_ERROR_INPUT, "hsi_scene_add_keyframe: target " + std::to_string(i) + " is not finite");
    const ShapeSetup& setup = ensure_setup(s);
    if (!s->scene.keyframes.empty()) solve_scene_keyframes(s->scene, setup);  // the start map must be certified
    const HarmonicMap start = s->scene.keyframes.empty() ? identity_map(setup.cage) : *s->scene.keyframes.back().coefficients;
    const KeyframeResult k = author_keyframe(setup, s->scene.handles, targets, start);
    if (!k.certified)
      fail(HSI_ERROR_NOT_CERTIFIED, "keyframe at time " + std::to_string(time) + " could not be certified: " + k.message);
    s->scene.keyframes.push_back({time, targets, k.map});
    if (report) {
      hsi_keyframe_report r{};
      r.certified = k.certified;
      r.reached = k.reached;
      r.max_target_error = k.max_target_error;
      r.worst_handle = k.worst_handle;
      r.iterations = k.iterations;
      r.energy = k.energy;
      r.ms = k.ms;
      std::snprintf(r.message, sizeof r.message, "%s", k.message.c_str());
      *report = r;
    }
  });
}

hsi_status hsi_scene_solve_keyframes(hsi_scene* s) {
  return guard([&] {
    require(s, "hsi_scene_solve_keyframes", "scene is NULL");
    solve_scene_keyframes(s->scene, ensure_setup(s));
  });
}

hsi_status hsi_scene_to_json(hsi_scene* s, char* buffer, size_t capacity, size_t* length) {
  return guard([&] {
    require(s, "hsi_scene_to_json", "scene is NULL");
    copy_out(scene_to_json(s->scene), buffer, capacity, length, true);
  });
}

hsi_status hsi_scene_save_file(hsi_scene* s, const char* path) {
  return guard([&] {
    require(s && path, "hsi_scene_save_file", "scene or path is NULL");
    save_scene(s->scene, path);
  });
}

// ---------------------------------------------------------------- interpolation

const char* hsi_backend_name(hsi_backend b) {
  switch (b) {
    case HSI_BACKEND_CPU: return "cpu";
    case HSI_BACKEND_AUTO: return "auto";
    case HSI_BACKEND_CUDA: return "cuda";
  }
  return "unknown backend";
}

int hsi_backend_available(hsi_backend b, const char** why) {
  static thread_local std::string reason;
  reason.clear();
  try {
    if (b == HSI_BACKEND_CPU || b == HSI_BACKEND_AUTO) return 1;
    if (b == HSI_BACKEND_CUDA) {
      const runtime::CudaStatus cuda = runtime::cuda_status();
      if (cuda.available) return 1;
      reason = cuda.detail;
    } else {
      reason = "unknown backend " + std::to_string(static_cast<int>(b));
    }
  } catch (...) {
    reason = "the backend could not be queried";
  }
  if (why) *why = reason.c_str();
  return 0;
}

void hsi_interpolation_options_default(hsi_interpolation_options* o) {
  if (!o) return;
  const InterpolationOptions d;
  o->tolerance = d.tolerance;
  o->max_iterations = d.max_iterations;
  o->projection = d.projection == HessianProjection::FullProj ? HSI_PROJECTION_FULLPROJ
                  : d.projection == HessianProjection::Delete ? HSI_PROJECTION_DELETE
                                                              : HSI_PROJECTION_PARTPROJ;  // the engine's default
  o->backend = HSI_BACKEND_CPU;
  o->timing = HSI_TIMING_SCENE;
}

hsi_status hsi_interpolator_create(hsi_scene* s, const hsi_interpolation_options* options, hsi_interpolator** out) {
  if (out) *out = nullptr;
  return guard([&] {
    require(s && out, "hsi_interpolator_create", "scene or out is NULL");
    hsi_interpolation_options o;
    hsi_interpolation_options_default(&o);
    if (options) o = *options;
    if (!(o.tolerance >= 0) || o.max_iterations < 1 || o.projection < HSI_PROJECTION_PARTPROJ || o.projection > HSI_PROJECTION_DELETE)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_interpolator_create: tolerance must be >= 0, max_iterations >= 1, projection 0, 1 or 2");
    if (o.backend != HSI_BACKEND_CPU && o.backend != HSI_BACKEND_AUTO && o.backend != HSI_BACKEND_CUDA)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_interpolator_create: backend " + std::to_string(static_cast<int>(o.backend)) +
                                           " is not HSI_BACKEND_CPU (0), HSI_BACKEND_AUTO (1) or HSI_BACKEND_CUDA (2)");
    if (o.timing < HSI_TIMING_SCENE || o.timing > HSI_TIMING_HOLD)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_interpolator_create: timing " + std::to_string(static_cast<int>(o.timing)) +
                                           " is not HSI_TIMING_SCENE (0), _LINEAR (1), _SMOOTH (2), _EASE (3) or _HOLD (4)");
    if (s->scene.keyframes.size() < 2)
      fail(HSI_ERROR_INPUT, "scene '" + s->scene.name + "': interpolation needs at least two keyframes (it has " +
                                std::to_string(s->scene.keyframes.size()) + ")");
    const ShapeSetup& setup = ensure_setup(s);
    solve_scene_keyframes(s->scene, setup);
    InterpolationOptions io;
    io.tolerance = o.tolerance;
    io.max_iterations = o.max_iterations;
    io.projection = o.projection == HSI_PROJECTION_FULLPROJ ? HessianProjection::FullProj
                    : o.projection == HSI_PROJECTION_DELETE ? HessianProjection::Delete
                                                            : HessianProjection::PartProj;
    static constexpr KeyTiming kTimings[] = {KeyTiming::Linear, KeyTiming::Linear, KeyTiming::Smooth, KeyTiming::Ease, KeyTiming::Hold};
    io.timing = o.timing == HSI_TIMING_SCENE ? scene_timings(s->scene) : std::vector<KeyTiming>{kTimings[o.timing]};
    std::vector<double> times;
    std::vector<HarmonicMap> maps;
    for (const Keyframe& k : s->scene.keyframes) {
      times.push_back(k.time);
      maps.push_back(*k.coefficients);
    }
    hsi_interpolator* h = new_handle<hsi_interpolator>();
    try {
      h->scene = std::make_shared<const Scene>(s->scene);
      h->setup = s->setup;
      const runtime::Backend requested = o.backend == HSI_BACKEND_CUDA ? runtime::Backend::Cuda
                                         : o.backend == HSI_BACKEND_AUTO ? runtime::Backend::Auto
                                                                         : runtime::Backend::Cpu;
      runtime::NewtonCoreChoice core = runtime::make_newton_core(*h->setup, requested);
      h->backend = core.choice;
      h->interp = std::make_unique<Interpolator>(*h->setup, times, maps, io, std::move(core.core), std::move(core.boundary));
    } catch (const runtime::BackendUnavailable& e) {
      delete_handle(h);
      fail(HSI_ERROR_UNSUPPORTED, std::string("hsi_interpolator_create: ") + e.what());
    } catch (...) {
      delete_handle(h);
      throw;
    }
    *out = h;
  });
}

void hsi_interpolator_destroy(hsi_interpolator* i) { delete_handle(i); }

hsi_status hsi_interpolator_time_range(hsi_interpolator* i, double* t_begin, double* t_end) {
  return guard([&] {
    require(i, "hsi_interpolator_time_range", "interpolator is NULL");
    if (t_begin) *t_begin = i->interp->t_begin();
    if (t_end) *t_end = i->interp->t_end();
  });
}

hsi_status hsi_interpolator_backend(const hsi_interpolator* i, hsi_backend_info* info) {
  return guard([&] {
    require(i && info, "hsi_interpolator_backend", "interpolator or info is NULL");
    auto to_c = [](runtime::Backend b) {
      return b == runtime::Backend::Cuda ? HSI_BACKEND_CUDA : b == runtime::Backend::Auto ? HSI_BACKEND_AUTO : HSI_BACKEND_CPU;
    };
    hsi_backend_info r{};
    r.requested = to_c(i->backend.requested);
    r.used = to_c(i->backend.used);
    std::snprintf(r.device, sizeof r.device, "%s", i->backend.device.c_str());
    std::snprintf(r.fallback, sizeof r.fallback, "%s", i->backend.fallback.c_str());
    *info = r;
  });
}

hsi_status hsi_interpolator_frame(hsi_interpolator* i, double t, hsi_sequence** out) {
  if (out) *out = nullptr;
  return guard([&] {
    require(i && out, "hsi_interpolator_frame", "interpolator or out is NULL");
    if (!std::isfinite(t)) fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_interpolator_frame: t is not finite");
    t = std::clamp(t, i->interp->t_begin(), i->interp->t_end());
    hsi_sequence* s = new_handle<hsi_sequence>();
    try {
      s->scene = i->scene;
      s->seq.setup = i->setup;
      s->seq.options = i->interp->options();  // so the report records what was used
      s->seq.frames.push_back(i->interp->frame(t, i->warm));
      s->seq.total_s = s->seq.frames.back().ms / 1000;
      if (s->seq.frames.back().certified) i->warm = s->seq.frames.back().x;
    } catch (...) {
      delete_handle(s);
      throw;
    }
    *out = s;
  });
}

hsi_status hsi_interpolator_sequence(hsi_interpolator* i, uint32_t frame_count, hsi_progress_fn progress, void* user, hsi_sequence** out) {
  if (out) *out = nullptr;
  return guard([&] {
    require(i && out, "hsi_interpolator_sequence", "interpolator or out is NULL");
    if (frame_count < 2 || frame_count > 10000000)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_interpolator_sequence: frame_count must be in [2, 1e7], got " + std::to_string(frame_count));
    struct Cancelled {};
    hsi_sequence* s = new_handle<hsi_sequence>();
    try {
      s->scene = i->scene;
      s->seq.setup = i->setup;
      s->seq.options = i->interp->options();
      const auto t0 = std::chrono::steady_clock::now();
      s->seq.frames = i->interp->sequence(static_cast<int>(frame_count), [&](const FrameResult& f, int k, int n) {
        if (!progress) return;
        const hsi_frame_report r = to_report(f);
        if (progress(static_cast<uint32_t>(k), static_cast<uint32_t>(n), &r, user)) throw Cancelled{};
      });
      s->seq.total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (auto it = s->seq.frames.rbegin(); it != s->seq.frames.rend(); ++it)
        if (it->certified) {
          i->warm = it->x;
          break;
        }
    } catch (const Cancelled&) {
      delete_handle(s);
      fail(HSI_ERROR_CANCELLED, "hsi_interpolator_sequence: cancelled by the progress callback");
    } catch (...) {
      delete_handle(s);
      throw;
    }
    *out = s;
  });
}

// ---------------------------------------------------------------- batches

void hsi_batch_options_default(hsi_batch_options* o) {
  if (!o) return;
  *o = hsi_batch_options{};
  o->struct_size = sizeof(hsi_batch_options);
  o->workers = 0;
  o->threads_per_worker = 1;
}

namespace {
// A failed sequence's exception as a status (its message is the batch's, naming the sequence).
hsi_status batch_status(const BatchSequenceResult& r) {
  if (r.cancelled) return HSI_ERROR_CANCELLED;
  try {
    if (r.exception) std::rethrow_exception(r.exception);
  } catch (const InputError&) {
    return HSI_ERROR_INPUT;
  } catch (const runtime::BackendUnavailable&) {
    return HSI_ERROR_UNSUPPORTED;
  } catch (const std::bad_alloc&) {
    return HSI_ERROR_OUT_OF_MEMORY;
  } catch (...) {
  }
  return HSI_ERROR_INTERNAL;
}
}  // namespace

hsi_status hsi_interpolators_sequence_batch(hsi_interpolator* const* interpolators, const uint32_t* frame_counts, uint32_t count,
                                            const hsi_batch_options* options, hsi_batch_progress_fn progress, void* user,
                                            hsi_sequence** out, hsi_status* statuses) {
  if (out)
    for (uint32_t k = 0; k < count; ++k) out[k] = nullptr;
  return guard([&] {
    const char* fn = "hsi_interpolators_sequence_batch";
    require(count == 0 || (interpolators && frame_counts && out), fn, "interpolators, frame_counts or out is NULL");
    hsi_batch_options o;
    hsi_batch_options_default(&o);
    if (options) {
      if (options->struct_size < sizeof(hsi_batch_options))
        fail(HSI_ERROR_INVALID_ARGUMENT, std::string(fn) + ": options->struct_size is " + std::to_string(options->struct_size) +
                                             ", expected " + std::to_string(sizeof(hsi_batch_options)) +
                                             " (set it with hsi_batch_options_default)");
      o = *options;
    }
    if (o.workers > 4096 || o.threads_per_worker > 4096)
      fail(HSI_ERROR_INVALID_ARGUMENT, std::string(fn) + ": workers and threads_per_worker must be at most 4096");
    for (uint32_t k = 0; k < count; ++k) {
      if (!interpolators[k]) fail(HSI_ERROR_INVALID_ARGUMENT, std::string(fn) + ": interpolator " + std::to_string(k) + " is NULL");
      if (frame_counts[k] < 2 || frame_counts[k] > 10000000)
        fail(HSI_ERROR_INVALID_ARGUMENT, std::string(fn) + ": frame_counts[" + std::to_string(k) + "] must be in [2, 1e7], got " +
                                             std::to_string(frame_counts[k]));
      if (interpolators[k]->backend.used != interpolators[0]->backend.used)
        fail(HSI_ERROR_INVALID_ARGUMENT, std::string(fn) + ": interpolator " + std::to_string(k) + " uses the " +
                                             std::string(runtime::to_string(interpolators[k]->backend.used)) + " core, interpolator 0 the " +
                                             std::string(runtime::to_string(interpolators[0]->backend.used)) +
                                             " core: a batch runs on one");
    }
    if (count == 0) return;
    std::vector<BatchSequence> batch(count);
    for (uint32_t k = 0; k < count; ++k) {
      const hsi_interpolator& i = *interpolators[k];
      BatchSequence& q = batch[k];
      q.name = "sequence " + std::to_string(k) + " (scene '" + i.scene->name + "')";
      q.setup = i.setup.get();
      for (const Keyframe& kf : i.scene->keyframes) {
        q.key_times.push_back(kf.time);
        q.keyframes.push_back(*kf.coefficients);
      }
      q.options = i.interp->options();
      q.times = sequence_times({i.interp->t_begin(), i.interp->t_end()}, static_cast<int>(frame_counts[k]));
    }
    BatchOptions bo;
    bo.workers = o.workers > 0 ? static_cast<int>(o.workers) : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    bo.threads_per_worker = static_cast<int>(o.threads_per_worker);
    const runtime::Backend used = interpolators[0]->backend.used;
    const runtime::CudaStatus cuda = used == runtime::Backend::Cpu ? runtime::CudaStatus{} : runtime::cuda_status();
    runtime::set_batch_backend(bo, used, cuda);
    const BatchResult r = solve_batch(batch, bo, [&](const FrameResult& f, int s, int i, size_t done, size_t total) {
      if (!progress) return true;
      const hsi_frame_report rep = to_report(f);
      return progress(static_cast<uint32_t>(s), static_cast<uint32_t>(i), done, total, &rep, user) == 0;
    });
    // Every sequence's handle first (none leaks if one cannot be made), then the statuses.
    std::vector<hsi_sequence*> made(count, nullptr);
    try {
      for (uint32_t k = 0; k < count; ++k) {
        if (!r.sequences[k].error.empty()) continue;
        made[k] = new_handle<hsi_sequence>();
        made[k]->scene = interpolators[k]->scene;
        made[k]->seq.setup = interpolators[k]->setup;
        made[k]->seq.options = batch[k].options;
        made[k]->seq.frames = r.sequences[k].frames;
        made[k]->seq.total_s = r.stats.seconds;
      }
    } catch (...) {
      for (hsi_sequence* h : made) delete_handle(h);
      throw;
    }
    std::string errors;
    hsi_status first = HSI_OK;
    for (uint32_t k = 0; k < count; ++k) {
      const hsi_status st = r.sequences[k].error.empty() ? HSI_OK : batch_status(r.sequences[k]);
      if (statuses) statuses[k] = st;
      out[k] = made[k];
      if (st == HSI_OK) {
        for (auto it = made[k]->seq.frames.rbegin(); it != made[k]->seq.frames.rend(); ++it)
          if (it->certified) {
            interpolators[k]->warm = it->x;
            break;
          }
        continue;
      }
      if (first == HSI_OK) first = st;
      errors += (errors.empty() ? "" : "; ") + r.sequences[k].error + " (" + hsi_status_name(st) + ")";
    }
    if (first != HSI_OK)
      fail(first, std::string(fn) + ": " + std::to_string(r.failed()) + " of " + std::to_string(count) + " sequences failed: " + errors);
  });
}

// ---------------------------------------------------------------- sequences

void hsi_sequence_destroy(hsi_sequence* s) { delete_handle(s); }

uint32_t hsi_sequence_frame_count(const hsi_sequence* s) { return s ? static_cast<uint32_t>(s->seq.frames.size()) : 0; }

hsi_status hsi_sequence_frame_report(const hsi_sequence* s, uint32_t frame, hsi_frame_report* report) {
  return guard([&] {
    const FrameResult& f = frame_of(s, frame, "hsi_sequence_frame_report");
    require(report, "hsi_sequence_frame_report", "report is NULL");
    *report = to_report(f);
  });
}

hsi_status hsi_sequence_summary_get(const hsi_sequence* s, hsi_sequence_summary* out) {
  return guard([&] {
    require(s && out, "hsi_sequence_summary_get", "sequence or summary is NULL");
    const SequenceSummary m = summarize(s->seq.frames, s->seq.total_s);
    hsi_sequence_summary r{};
    r.frames = static_cast<uint32_t>(m.frames);
    r.certified = static_cast<uint32_t>(m.certified);
    r.uncertified = static_cast<uint32_t>(m.uncertified);
    r.within_bounds = static_cast<uint32_t>(m.within_bounds);
    r.mean_iterations = m.mean_iterations;
    r.mean_ms = m.mean_ms;
    r.max_ms = m.max_ms;
    r.total_s = m.total_s;
    r.max_bound_excess = m.max_bound_excess;
    r.overlapping = static_cast<uint32_t>(m.overlapping);
    r.not_converged = static_cast<uint32_t>(m.not_converged);
    r.within_certified_bounds = static_cast<uint32_t>(m.within_certified_bounds);
    r.max_certified_bound_excess = m.max_certified_bound_excess;
    for (int k = 0; k < HSI_STOP_COUNT; ++k) r.stops[k] = static_cast<uint32_t>(m.stops[static_cast<size_t>(k)]);
    *out = r;
  });
}

hsi_status hsi_sequence_report_json(const hsi_sequence* s, char* buffer, size_t capacity, size_t* length) {
  return guard([&] {
    require(s, "hsi_sequence_report_json", "sequence is NULL");
    copy_out(report_json(*s->scene, s->seq), buffer, capacity, length, true);
  });
}

hsi_status hsi_sequence_report_csv(const hsi_sequence* s, char* buffer, size_t capacity, size_t* length) {
  return guard([&] {
    require(s, "hsi_sequence_report_csv", "sequence is NULL");
    copy_out(report_csv(s->seq), buffer, capacity, length, true);
  });
}

hsi_status hsi_sequence_evaluate(const hsi_sequence* s, uint32_t frame, const double* points_xy, size_t count, double* out_xy) {
  return guard([&] {
    const FrameResult& f = frame_of(s, frame, "hsi_sequence_evaluate");
    require((points_xy && out_xy) || count == 0, "hsi_sequence_evaluate", "points or out is NULL");
    const std::vector<cd> pts = read_points(points_xy, count);
    check_in_cage(s->seq.setup->cage, s->seq.setup->size, pts);
    const VectorXcd v = evaluate_map(evaluate_basis(s->seq.setup->cage, pts, kBasisC), f.map).f;
    for (size_t i = 0; i < count; ++i) {
      out_xy[2 * i] = v(static_cast<Eigen::Index>(i)).real();
      out_xy[2 * i + 1] = v(static_cast<Eigen::Index>(i)).imag();
    }
  });
}

hsi_status hsi_sequence_coefficients(const hsi_sequence* s, uint32_t frame, double* phi, double* psi, uint32_t coefficient_count) {
  return guard([&] {
    const FrameResult& f = frame_of(s, frame, "hsi_sequence_coefficients");
    if (coefficient_count != static_cast<uint32_t>(f.map.phi.size()))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_sequence_coefficients: the cage has " + std::to_string(f.map.phi.size()) +
                                           " coefficients, not " + std::to_string(coefficient_count));
    for (Eigen::Index j = 0; j < f.map.phi.size(); ++j) {
      if (phi) {
        phi[2 * j] = f.map.phi(j).real();
        phi[2 * j + 1] = f.map.phi(j).imag();
      }
      if (psi) {
        psi[2 * j] = f.map.psi(j).real();
        psi[2 * j + 1] = f.map.psi(j).imag();
      }
    }
  });
}

// As hsi bake: the scene's texture rectangle for the stored mesh, its samples for the blend certificates.
static BakeOptions scene_bake_options(const hsi_sequence* s, int single_precision) {
  BakeOptions o;
  o.single_precision = single_precision != 0;
  o.texture_rect = s->scene->texture_rect_or_bounds();
  o.certificate_samples = s->scene->samples;
  return o;
}

hsi_status hsi_sequence_bake_file(const hsi_sequence* s, const char* path, int single_precision) {
  return guard([&] {
    require(s && path, "hsi_sequence_bake_file", "sequence or path is NULL");
    write_baked(path, s->scene->shape, s->seq.frame_file(), scene_bake_options(s, single_precision));
  });
}

hsi_status hsi_sequence_bake_memory(const hsi_sequence* s, int single_precision, void* buffer, size_t capacity, size_t* size) {
  return guard([&] {
    require(s, "hsi_sequence_bake_memory", "sequence is NULL");
    copy_out(encode_baked(s->scene->shape, s->seq.frame_file(), scene_bake_options(s, single_precision)), static_cast<char*>(buffer),
             capacity, size, false);
  });
}

hsi_status hsi_sequence_save_frames(const hsi_sequence* s, const char* path) {
  return guard([&] {
    require(s && path, "hsi_sequence_save_frames", "sequence or path is NULL");
    write_frames(path, s->seq.frame_file());
  });
}

// ---------------------------------------------------------------- rendering

void hsi_render_options_default(hsi_render_options* o) {
  if (!o) return;
  *o = hsi_render_options{};
  o->width = o->height = 512;
  o->background[0] = o->background[1] = o->background[2] = o->background[3] = 1.0f;
  o->draw_boundary = 1;
  o->mesh_vertices = 4000;
  o->msaa_samples = 4;
}

int hsi_render_available(const char** why) {
#ifdef HSI_CAPI_RENDER
  static thread_local std::string reason;
  try {
    if (hsi::capi::render_available(&reason)) return 1;
  } catch (...) {
    reason = "the Vulkan renderer could not be queried";
  }
  if (why) *why = reason.c_str();
  return 0;
#else
  if (why) *why = runtime::built::kNoVulkan;
  return 0;
#endif
}

hsi_status hsi_sequence_render(hsi_sequence* s, uint32_t frame, const hsi_render_options* options, uint8_t* rgba, size_t row_stride) {
  return guard([&] {
    frame_of(s, frame, "hsi_sequence_render");
    require(rgba, "hsi_sequence_render", "rgba is NULL");
    hsi_render_options o;
    hsi_render_options_default(&o);
    if (options) o = *options;
    if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_sequence_render: width and height must be in [1, 16384]");
    if (row_stride != 0 && row_stride < 4 * static_cast<size_t>(o.width))
      fail(HSI_ERROR_INVALID_ARGUMENT, "hsi_sequence_render: row_stride is smaller than 4 * width");
#ifdef HSI_CAPI_RENDER
    hsi::capi::render_frame(*s, frame, o, rgba, row_stride ? row_stride : 4 * static_cast<size_t>(o.width));
#else
    fail(HSI_ERROR_UNSUPPORTED, std::string("hsi_sequence_render: ") + runtime::built::kNoVulkan);
#endif
  });
}

}  // extern "C"
