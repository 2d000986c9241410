/* hsi C API: harmonic shape interpolation of 2D shapes with holes, for game engines
 * and other hosts that speak C. One header, C99, opaque handles with explicit
 * create/destroy, status codes plus a message; no C++ exception ever crosses it.
 *
 *   hsi_scene         a shape, its cage, texture, handles and keyframes (a scene file)
 *   hsi_interpolator  the keyframes made certified, ready to make frames
 *   hsi_sequence      interpolated frames: their report, their maps (evaluate them at
 *                     your own points, e.g. a mesh's vertices), baking, rendering
 *
 * Errors: every function that can fail returns an hsi_status; on failure
 * hsi_last_error() gives a message that says what was wrong and where (file, JSON
 * path, keyframe, point index, ...). Out-parameters are left unchanged on failure,
 * out-handles set to NULL.
 *
 * Threads: the library is thread-compatible. Functions marked [any thread] may be
 * called concurrently with anything. [per handle] means: concurrent calls on
 * different handles are fine, calls on the same handle must not overlap (const
 * query functions on the same handle may overlap each other). Handles keep what
 * they need alive: an interpolator or sequence stays valid after the scene it came
 * from is destroyed or changed.
 *
 * Memory: handles and everything else this API allocates for the caller go through
 * the allocator hooks (hsi_set_allocator), as do the baked runtime's allocations;
 * the engine's internal working memory during a call uses the C++ heap.
 */
#ifndef HSI_HSI_H
#define HSI_HSI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(HSI_BUILDING_SHARED) && (defined(__GNUC__) || defined(__clang__))
#define HSI_API __attribute__((visibility("default")))
#else
#define HSI_API
#endif

#define HSI_VERSION_MAJOR 0
#define HSI_VERSION_MINOR 4
#define HSI_VERSION_PATCH 0
/* major * 10000 + minor * 100 + patch, comparable with hsi_version(). Before 1.0 the
 * minor version is the ABI: a struct that grows (0.2: hsi_interpolation_options gained
 * its backend; 0.3: hsi_frame_report and hsi_sequence_summary gained the certified
 * bounds and the frames that did not converge; 0.4: they gained why each solve
 * stopped) bumps it, and so the library's soname (libhsi.so.0.4). */
#define HSI_VERSION (HSI_VERSION_MAJOR * 10000 + HSI_VERSION_MINOR * 100 + HSI_VERSION_PATCH)
#define HSI_VERSION_STRING "0.4.0"

typedef enum hsi_status {
  HSI_OK = 0,
  HSI_ERROR_INVALID_ARGUMENT = 1, /* NULL handle or pointer, size or option out of its range */
  HSI_ERROR_INPUT = 2,            /* a scene, keyframe, file content or point was refused */
  HSI_ERROR_IO = 3,               /* a file cannot be read or written */
  HSI_ERROR_NOT_CERTIFIED = 4,    /* a map could not be certified locally injective */
  HSI_ERROR_OUT_OF_RANGE = 5,     /* a frame index past the end */
  HSI_ERROR_UNSUPPORTED = 6,      /* e.g. rendering in a build without Vulkan */
  HSI_ERROR_OUT_OF_MEMORY = 7,
  HSI_ERROR_BUFFER_TOO_SMALL = 8, /* *length or *size says how many bytes are needed */
  HSI_ERROR_CANCELLED = 9,        /* a progress callback asked to stop */
  HSI_ERROR_INTERNAL = 10         /* a bug: please report it with the message */
} hsi_status;

/* [any thread] The runtime version (HSI_VERSION of the library that is loaded) and
 * its string. Compare with HSI_VERSION to detect a header/library mismatch. */
HSI_API uint32_t hsi_version(void);
HSI_API const char* hsi_version_string(void);
/* [any thread] "invalid argument", "not certified", ... */
HSI_API const char* hsi_status_name(hsi_status status);
/* [any thread] The message of the last failure on this thread ("" if none); valid
 * until the next hsi_ call on this thread. */
HSI_API const char* hsi_last_error(void);

typedef struct hsi_allocator {
  void* (*allocate)(size_t size, size_t alignment, void* user); /* NULL on failure */
  void (*release)(void* pointer, void* user);
  void* user;
} hsi_allocator;
/* [not thread-safe] Installs allocator hooks (NULL: the C library's). Only while no
 * handle exists: otherwise HSI_ERROR_INVALID_ARGUMENT. */
HSI_API hsi_status hsi_set_allocator(const hsi_allocator* allocator);

typedef struct hsi_scene hsi_scene;
typedef struct hsi_interpolator hsi_interpolator;
typedef struct hsi_sequence hsi_sequence;

/* ------------------------------------------------------------------ scenes */

/* [any thread] A scene from a file (JSON, format in README.md, section "Scene files",
 * installed in share/doc/hsi) or from JSON text in memory; base_dir resolves the
 * texture (NULL: the working directory). The shape and any user cage are validated. */
HSI_API hsi_status hsi_scene_load_file(const char* path, hsi_scene** out);
HSI_API hsi_status hsi_scene_load_memory(const char* json, size_t size, const char* base_dir, hsi_scene** out);
/* [per handle] NULL is ignored. */
HSI_API void hsi_scene_destroy(hsi_scene* scene);

typedef struct hsi_scene_info {
  uint32_t loop_count;        /* 1 + holes */
  uint32_t hole_count;
  uint32_t cage_vertex_count; /* m (the cage is built on first need when the file has none) */
  uint32_t coefficient_count; /* m + holes: phi and psi each */
  uint32_t handle_count;
  uint32_t keyframe_count;
  uint32_t samples;           /* |G| in use */
  double hessian_ratio;
  double bbox[4];             /* the shape's bounding box x0, y0, x1, y1 */
  double size;                /* its diagonal: the unit of every tolerance */
  int has_texture;
} hsi_scene_info;
/* [per handle] */
HSI_API hsi_status hsi_scene_get_info(hsi_scene* scene, hsi_scene_info* info);

/* [per handle] Overrides the scene's |G| and Hessian ratio r (0: keep the scene's). */
HSI_API hsi_status hsi_scene_set_sampling(hsi_scene* scene, uint32_t samples, double hessian_ratio);

/* [per handle] Handles: points on the shape (x, y pairs) that keyframes pose. Setting
 * them removes the keyframes that were posed by targets for other handles. */
HSI_API hsi_status hsi_scene_set_handles(hsi_scene* scene, const double* xy, uint32_t count);
/* [per handle] Copies up to capacity handles; *count gets how many there are. */
HSI_API hsi_status hsi_scene_get_handles(hsi_scene* scene, double* xy, uint32_t capacity, uint32_t* count);

typedef struct hsi_keyframe_report {
  int certified;           /* always 1 for a keyframe that was added */
  int reached;             /* every handle within 1e-3 of the size of its target */
  double max_target_error; /* shape units */
  int worst_handle;        /* -1 when there are no handles */
  int iterations;          /* Newton iterations over all stages */
  double energy;           /* mean symmetric Dirichlet energy on the boundary (2 = isometric) */
  double ms;
  char message[256];
} hsi_keyframe_report;

/* [per handle] Removes every keyframe. */
HSI_API hsi_status hsi_scene_clear_keyframes(hsi_scene* scene);
/* [per handle] Authors a keyframe now: the handles dragged to targets (x, y pairs,
 * one per handle) from the previous keyframe's map (the identity for the first),
 * certified locally injective by construction. time must exceed the last
 * keyframe's. If the targets cannot be reached without folding, the closest
 * certified pose is added and report->reached is 0. report may be NULL. */
HSI_API hsi_status hsi_scene_add_keyframe(hsi_scene* scene, double time, const double* targets_xy, uint32_t count,
                                          hsi_keyframe_report* report);
/* [per handle] Makes every keyframe of the scene certified: keyframes loaded with
 * coefficients are certified, those with only targets are solved. Called by
 * hsi_interpolator_create too. HSI_ERROR_INPUT names a keyframe that cannot be made
 * certified (and why). */
HSI_API hsi_status hsi_scene_solve_keyframes(hsi_scene* scene);
/* [per handle] The scene as JSON (with solved keyframes' coefficients): copies up to
 * capacity bytes (NUL-terminated when it fits), *length = bytes needed without the
 * NUL; HSI_ERROR_BUFFER_TOO_SMALL when capacity <= *length. */
HSI_API hsi_status hsi_scene_to_json(hsi_scene* scene, char* buffer, size_t capacity, size_t* length);
/* [per handle] Writes the scene file atomically. */
HSI_API hsi_status hsi_scene_save_file(hsi_scene* scene, const char* path);

/* ------------------------------------------------------------------ interpolation */

typedef enum hsi_projection { HSI_PROJECTION_PARTPROJ = 0, HSI_PROJECTION_FULLPROJ = 1, HSI_PROJECTION_DELETE = 2 } hsi_projection;

/* Which Newton core solves the frames (the same choice as `hsi interpolate --backend`).
 * CPU: the reference (OpenMP over the samples). CUDA: the GPU core, the whole solve on
 * the device; an error (HSI_ERROR_UNSUPPORTED, saying why) where this library was built
 * without CUDA or no device can run it. AUTO: CUDA where it can run, else the CPU, and
 * hsi_interpolator_backend says why it fell back. Keyframes are solved on the CPU. */
typedef enum hsi_backend { HSI_BACKEND_CPU = 0, HSI_BACKEND_AUTO = 1, HSI_BACKEND_CUDA = 2 } hsi_backend;
/* [any thread] "cpu", "auto", "cuda" ("unknown backend" for another value). */
HSI_API const char* hsi_backend_name(hsi_backend backend);
/* [any thread] 1 when this library can run the backend here (CPU and AUTO always),
 * else 0; *why (may be NULL) gets the reason when 0, valid until the next call on this
 * thread. */
HSI_API int hsi_backend_available(hsi_backend backend, const char** why);

/* How keyframe intervals are travelled (the scene file's per-keyframe "timing"; README
 * "Timing through keyframes"). SCENE: each keyframe's own (linear where none is given);
 * the others apply to every interval. */
typedef enum hsi_timing {
  HSI_TIMING_SCENE = 0,
  HSI_TIMING_LINEAR = 1, /* the paper's linear blend of the metrics */
  HSI_TIMING_SMOOTH = 2, /* C1 through the keyframes (log-Euclidean cubic Hermite) */
  HSI_TIMING_EASE = 3,   /* ease in and out */
  HSI_TIMING_HOLD = 4    /* each keyframe held until the next */
} hsi_timing;

typedef struct hsi_interpolation_options {
  double tolerance;        /* stop a frame when E_k - E_k+1 < tolerance * E_k (relative); default 5e-8 */
  int max_iterations;      /* Newton iterations per frame; default 100 */
  hsi_projection projection; /* default HSI_PROJECTION_FULLPROJ (fewest iterations over the stress corpus); PARTPROJ is the paper's */
  hsi_backend backend;     /* default HSI_BACKEND_CPU (0.1's only core) */
  hsi_timing timing;       /* default HSI_TIMING_SCENE */
} hsi_interpolation_options;
/* [any thread] */
HSI_API void hsi_interpolation_options_default(hsi_interpolation_options* options);

/* [per handle: the scene] Certifies or solves the scene's keyframes (two or more)
 * and prepares interpolation. options may be NULL (defaults). */
HSI_API hsi_status hsi_interpolator_create(hsi_scene* scene, const hsi_interpolation_options* options,
                                           hsi_interpolator** out);
HSI_API void hsi_interpolator_destroy(hsi_interpolator* interpolator);
/* [per handle] The keyframes' time range. */
HSI_API hsi_status hsi_interpolator_time_range(hsi_interpolator* interpolator, double* t_begin, double* t_end);

typedef struct hsi_backend_info {
  hsi_backend requested; /* as in the options */
  hsi_backend used;      /* HSI_BACKEND_CPU or HSI_BACKEND_CUDA: the core that solves the frames */
  char device[128];      /* with CUDA: the device, e.g. "NVIDIA H100 80GB HBM3 (sm_90)"; else "" */
  char fallback[256];    /* why AUTO did not use CUDA (e.g. "no CUDA device (...)"); "" when it did or was not asked */
} hsi_backend_info;
/* [per handle, const] Which Newton core this interpolator uses, and why. */
HSI_API hsi_status hsi_interpolator_backend(const hsi_interpolator* interpolator, hsi_backend_info* info);

/* [per handle] One frame at time t (clamped to the range), warm-started from this
 * interpolator's previous frame if it made one: a one-frame sequence. A frame that
 * cannot be certified is returned and reported as such (certified = 0), never as good. */
HSI_API hsi_status hsi_interpolator_frame(hsi_interpolator* interpolator, double t, hsi_sequence** out);

/* 0.4. Why a frame's Newton solve stopped (hsi_frame_report.stop). Every value but
 * HSI_STOP_CONVERGED is a frame that did not converge (hsi_frame_report.converged == 0). */
typedef enum hsi_stop {
  HSI_STOP_CONVERGED = 0,           /* the decrement, the decrease or the slope fell below its tolerance */
  HSI_STOP_ITERATION_LIMIT = 1,     /* the iteration cap was reached, still decreasing */
  HSI_STOP_STAGNATED = 2,           /* the energy decreased only linearly and slowly, step after step */
  HSI_STOP_CERTIFICATE_REFUSED = 3, /* every step that lowered the energy enough was refused by the certificate */
  HSI_STOP_NO_DECREASE = 4,         /* the line search refused every step (the certificate refused none) */
  HSI_STOP_NOT_FACTORED = 5,        /* no Newton system could be factored */
  HSI_STOP_START_FOLDS = 6,         /* the starting map folds or degenerates at a sample */
  HSI_STOP_START_NOT_CERTIFIED = 7  /* the starting map is not certified */
} hsi_stop;
#define HSI_STOP_COUNT 8
/* [any thread] "converged", "iteration limit", "stagnated", "certificate refused",
 * "no decrease", "not factored", "start folds", "start not certified"; "unknown"
 * for any other value. */
HSI_API const char* hsi_stop_name(int stop);

typedef struct hsi_frame_report {
  double t;
  int keyframe, certified, converged;
  int iterations;
  double energy;        /* mean isometric energy against the blended metric (2 = exact) */
  double ms;
  /* Distortion SAMPLED at the certificate's breakpoints on the boundary (observed
   * values, not bounds: a denser sampling can exceed them). */
  double sigma1_max, sigma2_min, conformal_max, isometric_max;
  double bound_sigma1_max, bound_sigma2_min, bound_conformal_max, bound_isometric_max; /* keyframes' envelope of the same */
  double bound_excess;  /* relative excess of the sampled values over that envelope (0 = within) */
  /* The image of the shape's boundary crosses itself (the frame is locally injective
   * at most, not globally: two layers of the shape overlap), sampled at the boundary
   * breakpoints (README.md, section "Global overlap"); crossings: how many segment pairs. */
  int overlaps, crossings;
  /* 0.3. held: t lies in a Hold interval and the frame is the held keyframe itself. */
  int held;
  /* CERTIFIED bounds over the whole shape, from the certificate: sigma1 and
   * conformal (sigma1/sigma2) and isometric upper bounds, sigma2 a LOWER bound. NaN
   * when the frame is not certified. */
  double certified_sigma1_max, certified_sigma2_min, certified_conformal_max, certified_isometric_max;
  /* The two neighbouring keyframes' envelope of their certified bounds, and the
   * relative excess of this frame's certified bounds over it (0 = within; NaN when
   * the frame is not certified). */
  double certified_bound_sigma1_max, certified_bound_sigma2_min, certified_bound_conformal_max,
      certified_bound_isometric_max;
  double certified_bound_excess;
  /* 0.4. Why the solve stopped (hsi_stop); HSI_STOP_CONVERGED for a keyframe or a
   * held frame, which are not solved. converged == (stop == HSI_STOP_CONVERGED). */
  int stop;
} hsi_frame_report;

/* Called after each frame; return non-zero to stop (HSI_ERROR_CANCELLED). */
typedef int (*hsi_progress_fn)(uint32_t frame, uint32_t frame_count, const hsi_frame_report* report, void* user);

/* [per handle] frame_count (>= 2) frames uniform over the time range, each
 * warm-started from the previous one, as `hsi interpolate` makes them. */
HSI_API hsi_status hsi_interpolator_sequence(hsi_interpolator* interpolator, uint32_t frame_count, hsi_progress_fn progress,
                                             void* user, hsi_sequence** out);

/* ------------------------------------------------------------------ batches */

/* Many sequences solved together by a pool of worker threads (`hsi bake a.json b.json
 * -o DIR` uses the same engine code): each worker keeps its own Newton core per shape,
 * and a sequence's runs of frames between keyframe frames (frames at a keyframe time,
 * or held) are solved apart, as they do not depend on each other. */
typedef struct hsi_batch_options {
  uint32_t struct_size;        /* sizeof(hsi_batch_options), set by hsi_batch_options_default: the
                                  version of this struct (it may grow at its end) */
  uint32_t workers;            /* worker threads; 0 (default): the machine's hardware threads */
  uint32_t threads_per_worker; /* OpenMP threads in each worker (the CPU core's sample loops);
                                  default 1. The CPU core's frames follow this count in their last
                                  bits (its energy is an OpenMP sum), never the number of workers */
} hsi_batch_options;
/* [any thread] */
HSI_API void hsi_batch_options_default(hsi_batch_options* options);

/* After each frame of a batch: which sequence and frame, frames done so far of all the
 * batch's, and the frame's report. Called from the workers, one call at a time, frames
 * of different sequences interleaved. Return non-zero to stop the batch. */
typedef int (*hsi_batch_progress_fn)(uint32_t sequence, uint32_t frame, uint64_t done, uint64_t total,
                                     const hsi_frame_report* report, void* user);

/* [per handle: every interpolator] Solves count sequences together: sequence k is
 * frame_counts[k] (>= 2) frames of interpolators[k], the same frames as
 * hsi_interpolator_sequence(interpolators[k], frame_counts[k], ...) makes (bit for bit
 * when that runs with threads_per_worker OpenMP threads; for any number of workers), on
 * the Newton core the interpolators use (hsi_interpolator_backend), which must be the
 * same for all of them. out[k] gets the sequence, or NULL when it failed; statuses[k]
 * (statuses may be NULL) its status. A sequence that fails does not stop the others.
 * Returns HSI_OK when every sequence was solved, else the status of the first that was
 * not, and hsi_last_error() names every failed sequence (its index and scene) and why.
 * A frame that cannot be certified is no failure: its sequence reports it (certified =
 * 0). Afterwards each interpolator warm-starts hsi_interpolator_frame from its
 * sequence's last certified frame, as after hsi_interpolator_sequence. progress may be
 * NULL; when it stops the batch, the unfinished sequences get HSI_ERROR_CANCELLED.
 * options may be NULL (defaults). */
HSI_API hsi_status hsi_interpolators_sequence_batch(hsi_interpolator* const* interpolators, const uint32_t* frame_counts,
                                                    uint32_t count, const hsi_batch_options* options,
                                                    hsi_batch_progress_fn progress, void* user, hsi_sequence** out,
                                                    hsi_status* statuses);

/* ------------------------------------------------------------------ sequences */

HSI_API void hsi_sequence_destroy(hsi_sequence* sequence);
/* [per handle, const] */
HSI_API uint32_t hsi_sequence_frame_count(const hsi_sequence* sequence);
HSI_API hsi_status hsi_sequence_frame_report(const hsi_sequence* sequence, uint32_t frame, hsi_frame_report* report);

typedef struct hsi_sequence_summary {
  /* within_bounds, max_bound_excess: SAMPLED distortion against the keyframes' sampled envelope */
  uint32_t frames, certified, uncertified, within_bounds;
  double mean_iterations, mean_ms, max_ms, total_s, max_bound_excess;
  uint32_t overlapping; /* frames that overlap themselves (hsi_frame_report.overlaps) */
  /* 0.3. Frames whose solve stopped without meeting its tolerance (certified or not:
   * hsi_frame_report.converged == 0); `hsi interpolate` exits 4 for these. */
  uint32_t not_converged;
  /* Certified frames whose certified bounds lie within the keyframes' certified
   * envelope, and the largest certified excess (certified frames only). */
  uint32_t within_certified_bounds;
  double max_certified_bound_excess;
  /* 0.4. Frames by why their solve stopped, indexed by hsi_stop; stops[HSI_STOP_CONVERGED]
   * + not_converged == frames. */
  uint32_t stops[HSI_STOP_COUNT];
} hsi_sequence_summary;
/* [per handle, const] */
HSI_API hsi_status hsi_sequence_summary_get(const hsi_sequence* sequence, hsi_sequence_summary* summary);
/* [per handle, const] The report as JSON (the schema of `hsi interpolate`'s
 * report.json) or CSV (one line per frame); buffer protocol as hsi_scene_to_json. */
HSI_API hsi_status hsi_sequence_report_json(const hsi_sequence* sequence, char* buffer, size_t capacity, size_t* length);
HSI_API hsi_status hsi_sequence_report_csv(const hsi_sequence* sequence, char* buffer, size_t capacity, size_t* length);

/* [per handle, const] The frame's map f at count points (x, y pairs; e.g. a game
 * mesh's rest vertices) into out_xy (x, y pairs; may not alias points_xy). Points
 * must lie inside the cage (the shape and a margin around it): otherwise
 * HSI_ERROR_INPUT names the first point that does not. */
HSI_API hsi_status hsi_sequence_evaluate(const hsi_sequence* sequence, uint32_t frame, const double* points_xy, size_t count,
                                         double* out_xy);
/* [per handle, const] The frame's coefficients over the cage, (re, im) pairs:
 * phi and psi get 2 * coefficient_count doubles each (either may be NULL). */
HSI_API hsi_status hsi_sequence_coefficients(const hsi_sequence* sequence, uint32_t frame, double* phi, double* psi,
                                             uint32_t coefficient_count);

/* [per handle, const] Bakes the sequence for playback (the .hsib format and its
 * dependency-free runtime: hsi/baked_runtime.h). single_precision: coefficients as
 * f32 (compact) instead of f64. To memory: buffer protocol as hsi_scene_to_json, in
 * bytes (no NUL). */
HSI_API hsi_status hsi_sequence_bake_file(const hsi_sequence* sequence, const char* path, int single_precision);
HSI_API hsi_status hsi_sequence_bake_memory(const hsi_sequence* sequence, int single_precision, void* buffer, size_t capacity,
                                            size_t* size);
/* [per handle, const] Writes the frames file (.hsif) as `hsi interpolate` does. */
HSI_API hsi_status hsi_sequence_save_frames(const hsi_sequence* sequence, const char* path);

/* ------------------------------------------------------------------ rendering */

typedef struct hsi_render_options {
  uint32_t width, height;   /* pixels; default 512 x 512 */
  float background[4];      /* straight RGBA in [0, 1]; default opaque white */
  int draw_boundary;        /* the image of the outline and holes as lines; default 1 */
  int draw_distortion;      /* conformal distortion colour map over the texture; default 0 */
  int draw_handles;         /* default 0 */
  double mesh_vertices;     /* triangulation resolution, about this many vertices; default 4000 */
  double view[4];           /* world rectangle x0, y0, x1, y1 to show; all 0 (default): fit every
                               frame of the sequence, so frames share one view */
  uint32_t msaa_samples;    /* 1, 2, 4 or 8; default 4 */
} hsi_render_options;
/* [any thread] */
HSI_API void hsi_render_options_default(hsi_render_options* options);
/* [any thread] 1 when this library renders (built with Vulkan and a device, e.g.
 * lavapipe, is present), else 0; *why (may be NULL) gets the reason when 0. */
HSI_API int hsi_render_available(const char** why);
/* [per handle] Renders frame `frame` (textured with the scene's texture) into rgba:
 * height rows of width RGBA8 pixels (straight alpha), row_stride bytes apart
 * (0 = 4 * width), top row first. HSI_ERROR_UNSUPPORTED without Vulkan. The first
 * call sets up the renderer (seconds on a CPU device); later calls reuse it. With the
 * environment variable HSI_VULKAN_VALIDATION=1 the Khronos validation layer is on
 * and any message it reports fails the call (HSI_ERROR_INTERNAL, with the messages). */
HSI_API hsi_status hsi_sequence_render(hsi_sequence* sequence, uint32_t frame, const hsi_render_options* options,
                                       uint8_t* rgba, size_t row_stride);

#ifdef __cplusplus
}
#endif

#endif /* HSI_HSI_H */
