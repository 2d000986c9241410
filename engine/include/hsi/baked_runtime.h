/* Baked playback of an hsi sequence: a tiny, dependency-free C99 runtime (this header
 * and its source baked_runtime.c, nothing else) that plays a .hsib file back on any
 * render mesh (its own, or the shape's triangulation stored in the file). It
 * precomputes the mesh's basis rows once (Cauchy coordinates of the cage and one log
 * term per hole, written out below) and then makes each frame's vertices with one
 * small matrix product: vertex = rows(vertex) · W(frame) + translation; a binding
 * that opts in keeps the rows' derivatives too and reports each vertex's singular
 * values sigma1, sigma2 (its distortion, sampled) the same way. The same
 * products run in a vertex shader: hsi/hsib_playback.glsl with its preambles
 * hsi/hsib_preamble_vulkan.glsl and hsi/hsib_preamble_gl.glsl (OpenGL, WebGL2),
 * installed beside this header (hsib_gpu_* below fill its data). An
 * stb-style single-file copy of this runtime, hsib.h (installed too), is
 * generated from this header and baked_runtime.c at build time. More in README.md,
 * section "Game engines" (installed in share/doc/hsi).
 *
 * ---------------------------------------------------------------------------------
 * File format .hsib, version 2 (this runtime also reads version 1, which lacks the
 * parts marked "v2"). All integers and floats little-endian, IEEE 754.
 *
 * Header (96 bytes in version 1, 128 in version 2):
 *    0  char[4]  magic "HSIB"
 *    4  u32      format version (2; 1 still read)
 *    8  u32      header size in bytes (128; version 1: 96)
 *   12  u32      flags: bit 0 set = per-frame coefficients are f32, clear = f64;
 *                other bits 0
 *   16  u32      L  cage loops (>= 1; loop 0 encloses the shape, loop k lies in hole k)
 *   20  u32      m  cage vertices over all loops
 *   24  u32      N  holes (= L - 1)
 *   28  u32      R  basis row length (the runtime's columns)
 *   32  u32      D  reduced coefficients per frame
 *   36  u32      Z  non-zeros of the expansion matrix E
 *   40  u32      F  frames
 *   44  u32      S  bytes per frame record (= 48 + D * (4 or 8) + 4)
 *   48  f64[4]   the shape's bounding box x0, y0, x1, y1
 *   80  u64      bytes of the static section
 *   88  u32      CRC-32 of the static section
 * Version 1: 92 u32 CRC-32 of header bytes 0..91. Version 2:
 *   92  u32      k  blend sub-steps: the baker certified the blends (1 - s) f_i + s f_i+1
 *                at s = 1/k, ..., (k-1)/k of the intervals flagged 16 below (0: none)
 *   96  u32      P  mesh vertices (the shape's triangulation; 0 = none, then T = 0)
 *  100  u32      T  mesh triangles
 *  104  u32      Ls shape loops (the shape's outline: loop 0 outer, then its holes)
 *  108  u32      Ms shape vertices over all loops
 *  112  u32[3]   reserved (0)
 *  124  u32      CRC-32 of header bytes 0..123
 * Static section (once per file):
 *   L x u32             vertices per cage loop (each >= 3, summing to m)
 *   m x f64[2]          cage vertices z_j, loop by loop
 *   N x f64[2]          hole points rho_h
 *   R x u32             row sources, (column << 2) | part: part 0 = Re C_j(w),
 *                       part 1 = Im C_j(w) for cage vertex j = column < m;
 *                       part 2 = log|w - rho_h| for hole h = column < N
 *   Z x {u32 target, u32 source, f64 value}
 *                       E, the fixed expansion of the reduced coefficients x into
 *                       weights: w[target] += value * x[source], target < 2R
 *   v2: Ls x u32        vertices per shape loop (each >= 3, summing to Ms)
 *   v2: Ms x f64[2]     shape vertices, loop by loop
 *   v2: f64[4]          texture rectangle x0, y0, x1, y1: a rest point (x, y) has
 *                       texture coordinates u = (x - x0)/(x1 - x0), v = (y1 - y)/(y1 - y0)
 *                       (v = 0 is the image's top row, as glTF has it)
 *   v2: P x f32[2]      mesh vertices (rest positions)
 *   v2: T x u32[3]      mesh triangles, counter-clockwise
 * Frames (F records of S bytes each, then the end of the file):
 *    0  f64      time t
 *    8  u32      flags: 1 certified locally injective, 2 keyframe, 4 converged,
 *                8 overlaps itself (the image of the shape's boundary crosses
 *                itself at the sampled breakpoints: not globally injective);
 *                v2: 16 blend certified: both this frame and the next are
 *                certified and so is every blend at the k-1 sub-steps between
 *                them (the injectivity certificate of hsi, proved, not sampled);
 *                32 some sub-step blend of this interval overlaps itself (sampled
 *                like flag 8). 16 and 32 never on the last frame.
 *   12  u32      stop: why the frame's Newton solve stopped. 0: not recorded (files
 *                baked before hsi recorded it wrote 0 here, then reserved; and frames
 *                whose reason is not known, e.g. from a version 1 frames file); else
 *                bit 8 set and bits 0..7 the reason, an HSIB_STOP_* value (hsi_stop's
 *                numbers: 0 converged, 1 iteration limit, 2 stagnated, 3 certificate
 *                refused, 4 no decrease, 5 not factored, 6 start folds, 7 start not
 *                certified); bits 9..31 0. A recorded reason is 0 (converged) exactly
 *                when flag 4 is set. Runtimes that predate it ignore this word (in
 *                either version), so the format version stays 2.
 *   16  f64[2]   rotation r (unit complex number)
 *   32  f64[2]   translation c
 *   48  D x f32|f64  reduced coefficients x (hsi's gauge modulo rigid motions)
 *   S-4 u32      CRC-32 of the record's bytes 0..S-5
 * CRC-32 is the IEEE / zlib one (polynomial 0xEDB88320, initial and final xor ~0).
 *
 * A frame's map at a point w (any point inside the cage, not only on the shape) is
 *   f(w) = r * sum_k row_k(w) * (w[2k] + i w[2k+1]) + c,   w = E x,
 * where row_k(w) is the real basis function that row source k names: for cage
 * vertex j of a loop with neighbours z_{j-1}, z_{j+1}, B_j = z_j - w, A_j = z_j - z_{j-1},
 *   C_j(w) = 1/(2 pi i) [B_{j+1}/A_{j+1} log(B_{j+1}/B_j) - B_{j-1}/A_j log(B_j/B_{j-1})]
 * (the Cauchy coordinates of the cage, Weber et al. 2009), and log|w - rho_h| for a
 * hole (rho_h its hole point). For the
 * Cauchy column j with coefficients phi_j, psi_j of f = sum C phi + conj(sum C psi),
 * Re C_j weighs phi_j + conj(psi_j) and Im C_j weighs i (phi_j - conj(psi_j)); a
 * hole's log term weighs 2 phi_log (psi_log = conj phi_log). Reading back the
 * reduced x and the pose is how the file stays compact (D ~ 4 reals per cage vertex,
 * a few kilobytes per frame): E has at most 4 non-zeros per column.
 *
 * Why weights and not per-vertex rows over x: a vertex's row has R = 2(n - N) + N
 * floats (n active Cauchy columns) and serves both outputs, 2R multiply-adds; rows
 * over the reduced coefficients would need 2D = 2(4n - 2N - 5) floats and as many
 * multiply-adds. So bindings take a quarter of the memory and a frame half the
 * arithmetic (bench/bench_baked measures both); expanding x into w costs O(Z) per
 * frame, independent of the mesh.
 *
 * Blending between frames, and what is certified. The blend of two frames'
 * coefficients is again a harmonic map. `hsi bake` certifies it at the k - 1 sub-steps
 * s = j/k inside every interval whose two frames are certified (flag 16 when all
 * pass). hsib_blend_at_time picks what is shown at time t: HSIB_PLAY_CERTIFIED_STEPS
 * snaps s to the nearest sub-step, so every map shown was certified (k times the
 * frame rate); HSIB_PLAY_BLEND blends at the exact s, which is certified only at the
 * sub-steps (between them it is a harmonic map that nobody checked: the returned
 * flags say so); HSIB_PLAY_NEAREST shows the nearest frame. Where an interval lacks
 * flag 16 (or k < 2, or a version 1 file) every mode shows the nearest frame.
 *
 * Distortion (opt in: hsib_bind_flags with HSIB_BIND_DERIVATIVES). The Jacobian of
 * the map shown is, as the position, a product with the same weights:
 *   df/dx = r * sum_k (d row_k/dx)(w) * (w[2k] + i w[2k+1]),  df/dy likewise,
 * from each vertex's derivative rows, computed at bind time in closed form: the C_j
 * are holomorphic with C_j'(w) = 1/(2 pi i) [L_{j-1}/A_j - L_j/A_{j+1}],
 * L_j = log(B_{j+1}/B_j), so d/dx Re C_j = Re C_j', d/dy Re C_j = -Im C_j',
 * d/dx Im C_j = Im C_j', d/dy Im C_j = Re C_j'; and grad log|w - rho| = (w - rho)/|w - rho|^2.
 * With J = [a b; c d] (df/dx = (a, c), df/dy = (b, d)), f_z = ((a + d) + i(c - b))/2
 * and f_zbar = ((a - d) + i(c + b))/2, the runtime reports hsi's singular values
 *   sigma1 = |f_z| + |f_zbar|,  sigma2 = |f_z| - |f_zbar|
 * (sigma2 <= 0: the map folds or flips orientation at that vertex). hsi's distortion
 * measures follow from them: conformal sigma1/sigma2 and isometric (symmetric
 * Dirichlet) (sigma1^2 + sigma1^-2 + sigma2^2 + sigma2^-2)/2, both for sigma2 > 0.
 * These are SAMPLED values, the map's own at the bound vertices (float arithmetic:
 * about 1e-6 of sigma1 on hsi's tests, more near the cage, where the rows are large
 * and cancel), not the certificate's bounds: between vertices, and for a
 * blend between certified sub-steps, nothing is proved. A blend blends J linearly, as
 * it blends positions, and its sigma is that of the blended J (not the blend of the
 * two frames' sigma). A clamped vertex (HSIB_OUTSIDE_CLAMP) reports the Jacobian at
 * the point it was clamped to.
 *
 * Readers refuse, with a message naming the problem and the byte or frame: a wrong
 * magic, another version, a header or static-section checksum mismatch, impossible
 * sizes, a truncated file or trailing bytes, a frame whose checksum fails, and a
 * frame's unknown flags or stop word (an unknown stop code, or a reason that
 * contradicts flag 4).
 * ---------------------------------------------------------------------------------
 *
 * Thread safety: a sequence and a binding are immutable once made; any number of
 * threads may call hsib_evaluate / hsib_evaluate_range / hsib_evaluate_*distortion* /
 * the queries on them at once. hsib_set_allocator must be called before anything else and is not
 * thread-safe. Memory: only what hsib_* allocates, through the allocator hooks; or
 * none at all for a sequence and a binding placed in the caller's memory
 * (hsib_open_in_place, hsib_bind_options.memory): then only evaluation (positions or
 * distortion) with rows longer than R = 256, binding with cages whose 2m + 4 (largest
 * loop) exceeds 2048 (a single loop of 341 vertices; with HSIB_BIND_DERIVATIVES
 * 4m + 4 (largest loop), a single loop of 256), hsib_basis_row,
 * hsib_basis_row_derivatives, hsib_blend_weights and hsib_gpu_uniforms take scratch
 * from the hooks.
 *
 * ABI: the distortion calls (hsib_bind_flags and after) and the stop reasons
 * (hsib_frame_stop, hsib_stop_name) were added without changing any struct or existing
 * function, so a program built against a header without them runs unchanged; one that
 * calls them needs a library that has them.
 */
#ifndef HSI_BAKED_RUNTIME_H
#define HSI_BAKED_RUNTIME_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(HSI_BUILDING_SHARED) && (defined(__GNUC__) || defined(__clang__))
#define HSIB_API __attribute__((visibility("default")))
#else
#define HSIB_API
#endif

#define HSIB_FORMAT_VERSION 2
#define HSIB_HEADER_SIZE 128   /* version 2 */
#define HSIB_HEADER_SIZE_V1 96

#define HSIB_FRAME_CERTIFIED 1u
#define HSIB_FRAME_KEYFRAME 2u
#define HSIB_FRAME_CONVERGED 4u
#define HSIB_FRAME_OVERLAPS 8u /* the frame overlaps itself (see the frame record) */
#define HSIB_FRAME_BLEND_CERTIFIED 16u /* the blends toward the next frame are certified at the k-1 sub-steps */
#define HSIB_FRAME_BLEND_OVERLAPS 32u  /* some sub-step blend toward the next frame overlaps itself */
#define HSIB_BLEND_BLENDED 64u         /* in hsib_blend.flags: the map shown is a blend of two frames */

/* Why a frame's Newton solve stopped (hsib_frame_stop): hsi's hsi_stop values (hsi/hsi.h). */
#define HSIB_STOP_CONVERGED 0u
#define HSIB_STOP_ITERATION_LIMIT 1u     /* the iteration cap was reached, still decreasing */
#define HSIB_STOP_STAGNATED 2u           /* the energy decreased only linearly and slowly, step after step */
#define HSIB_STOP_CERTIFICATE_REFUSED 3u /* every step that lowered the energy enough was refused by the certificate */
#define HSIB_STOP_NO_DECREASE 4u         /* the line search refused every step (the certificate refused none) */
#define HSIB_STOP_NOT_FACTORED 5u        /* no Newton system could be factored */
#define HSIB_STOP_START_FOLDS 6u         /* the starting map folds or degenerates at a sample */
#define HSIB_STOP_START_NOT_CERTIFIED 7u /* the starting map is not certified */
#define HSIB_STOP_COUNT 8u
#define HSIB_STOP_NOT_RECORDED 255u      /* the file does not say (a frame without flag 4 in an older file) */

typedef enum hsib_status {
  HSIB_OK = 0,
  HSIB_ERROR_ARGUMENT = 1,   /* a null pointer, zero size, frame index out of range */
  HSIB_ERROR_IO = 2,         /* the file cannot be opened or read */
  HSIB_ERROR_FORMAT = 3,     /* not a baked file, or impossible sizes / values */
  HSIB_ERROR_VERSION = 4,    /* a format version this runtime does not read */
  HSIB_ERROR_TRUNCATED = 5,  /* the file ends early (or has trailing bytes) */
  HSIB_ERROR_CHECKSUM = 6,   /* a CRC-32 does not match: the file is corrupt */
  HSIB_ERROR_MEMORY = 7,     /* an allocation failed */
  HSIB_ERROR_DOMAIN = 8      /* a rest vertex lies outside the cage (or on it) */
} hsib_status;

typedef struct hsib_sequence hsib_sequence;
typedef struct hsib_binding hsib_binding;

typedef struct hsib_info {
  uint32_t version;
  uint32_t frame_count;
  uint32_t loop_count, cage_vertex_count, hole_count;
  uint32_t row_length;          /* R: floats per vertex in a binding */
  uint32_t coefficient_count;   /* D: reduced coefficients per frame */
  int single_precision;         /* per-frame coefficients stored as f32 */
  double bbox[4];               /* the shape's bounding box x0, y0, x1, y1 */
  double t_begin, t_end;
  size_t file_bytes;
  uint32_t blend_substeps;       /* k (0 or 1: no certified blends; version 1: 0) */
  uint32_t mesh_vertex_count;    /* the stored triangulation (version 1: 0) */
  uint32_t mesh_triangle_count;
  uint32_t shape_loop_count;     /* the stored outline (version 1: 0) */
  size_t sequence_bytes;         /* memory the opened sequence takes (hsib_sequence_bytes) */
} hsib_info;

/* The shape's triangulation as stored in the file; the arrays belong to the sequence. */
typedef struct hsib_mesh {
  uint32_t vertex_count, triangle_count;
  const float* xy;            /* rest positions, 2 floats per vertex */
  const float* uv;            /* texture coordinates, 2 floats per vertex (v = 0: the image's top row) */
  const uint32_t* triangles;  /* 3 vertex indices per triangle, counter-clockwise */
  double texture_rect[4];     /* the rest rectangle the texture covers: x0, y0, x1, y1 */
} hsib_mesh;

/* Where a rest point lies. */
typedef enum hsib_region {
  HSIB_REGION_OUTSIDE = 0, /* outside the cage domain: the map is not defined there (a clamped vertex) */
  HSIB_REGION_CAGE = 1,    /* inside the cage but not the shape (the margin): mapped, but the
                              certificate speaks of the shape only; version 1 files (no outline): any point inside the cage */
  HSIB_REGION_SHAPE = 2    /* inside the shape */
} hsib_region;

/* What a binding does with a rest vertex outside the cage domain. */
typedef enum hsib_outside {
  HSIB_OUTSIDE_REFUSE = 0, /* the whole bind fails with HSIB_ERROR_DOMAIN naming the first such vertex */
  HSIB_OUTSIDE_CLAMP = 1   /* the vertex follows the nearest point just inside the cage; its region says so */
} hsib_outside;

typedef struct hsib_bind_options {
  hsib_outside outside;    /* default HSIB_OUTSIDE_REFUSE */
  uint8_t* vertex_region;  /* optional, one byte per vertex: its hsib_region (OUTSIDE = clamped) */
  void* memory;            /* optional 16-byte aligned memory for the binding (hsib_binding_memory_size bytes) */
  size_t memory_bytes;
} hsib_bind_options;

/* How playback picks the map shown at a time (see "Blending between frames" above). */
typedef enum hsib_playback {
  HSIB_PLAY_NEAREST = 0,          /* the nearest frame */
  HSIB_PLAY_CERTIFIED_STEPS = 1,  /* blends, snapped to the baker's certified sub-steps */
  HSIB_PLAY_BLEND = 2             /* blends at the exact time; certified only at the sub-steps */
} hsib_playback;

/* The map shown: (1 - s) f_frame0 + s f_frame1 (frame0 == frame1, s = 0 for a frame). */
typedef struct hsib_blend {
  uint32_t frame0, frame1;
  float s;
  uint32_t flags;  /* HSIB_FRAME_CERTIFIED when the baker certified this very map, HSIB_FRAME_OVERLAPS,
                      HSIB_BLEND_BLENDED; for a frame, its own flags 1, 2, 4, 8 */
} hsib_blend;

typedef struct hsib_allocator {
  void* (*allocate)(size_t bytes, void* user);  /* NULL on failure; 16-byte aligned or better */
  void (*release)(void* pointer, void* user);
  void* user;
} hsib_allocator;

/* NULL restores malloc/free. Call before any other hsib_ function. */
HSIB_API void hsib_set_allocator(const hsib_allocator* allocator);

/* A short English name of a status ("checksum mismatch", ...). */
HSIB_API const char* hsib_status_name(hsib_status status);

/* Opens a baked sequence from memory (the bytes are copied) or from a file. On
 * failure *out is NULL and, when error is given, it holds a message of at most
 * error_size - 1 characters naming the problem and where. */
HSIB_API hsib_status hsib_open_memory(const void* data, size_t size, hsib_sequence** out, char* error,
                                      size_t error_size);
HSIB_API hsib_status hsib_open_file(const char* path, hsib_sequence** out, char* error, size_t error_size);
/* Into the caller's memory: hsib_sequence_bytes reads the header and says how much
 * (16-byte aligned); nothing is allocated, and hsib_close releases nothing. */
HSIB_API hsib_status hsib_sequence_bytes(const void* data, size_t size, size_t* bytes, char* error, size_t error_size);
HSIB_API hsib_status hsib_open_in_place(const void* data, size_t size, void* memory, size_t memory_bytes, hsib_sequence** out,
                                        char* error, size_t error_size);
HSIB_API void hsib_close(hsib_sequence* sequence);

HSIB_API void hsib_get_info(const hsib_sequence* sequence, hsib_info* info);
HSIB_API hsib_status hsib_frame_info(const hsib_sequence* sequence, uint32_t frame, double* t, uint32_t* flags);
/* Why the frame's Newton solve stopped: an HSIB_STOP_* value (the frame record's stop
 * word), or, where the file does not record it, HSIB_STOP_CONVERGED for a frame with
 * flag 4 (converged) and HSIB_STOP_NOT_RECORDED for one without. */
HSIB_API hsib_status hsib_frame_stop(const hsib_sequence* sequence, uint32_t frame, uint32_t* stop);
/* A short English name of a stop reason: "converged", "iteration limit", "stagnated",
 * "certificate refused", "no decrease", "not factored", "start folds", "start not
 * certified" (as hsi_stop_name), "not recorded" (HSIB_STOP_NOT_RECORDED), else "unknown". */
HSIB_API const char* hsib_stop_name(uint32_t stop);
/* The frame whose time is nearest t (clamped to the sequence). */
HSIB_API uint32_t hsib_frame_at_time(const hsib_sequence* sequence, double t);
/* The map to show at time t (clamped to the sequence), blended only where certified. */
HSIB_API hsib_blend hsib_blend_at_time(const hsib_sequence* sequence, double t, hsib_playback mode);

/* The stored triangulation of the shape (HSIB_ERROR_VERSION for version 1 files). */
HSIB_API hsib_status hsib_get_mesh(const hsib_sequence* sequence, hsib_mesh* mesh);
/* Where rest point (x, y) lies: in the shape, in the cage's margin, or outside. */
HSIB_API hsib_region hsib_point_region(const hsib_sequence* sequence, double x, double y);

/* Precomputes the basis rows of vertex_count rest vertices (x, y floats; stride in
 * bytes between vertices, 0 = tightly packed). Every vertex must lie inside the
 * cage's outer loop and outside its hole loops (the shape and a margin around it);
 * otherwise HSIB_ERROR_DOMAIN names the first vertex that does not. The binding
 * refers to the sequence, which must outlive it. hsib_bind_ex takes options
 * (NULL = hsib_bind): clamp vertices outside instead, report each vertex's region,
 * place the binding in the caller's memory. */
HSIB_API hsib_status hsib_bind(const hsib_sequence* sequence, const float* rest_xy, size_t vertex_count,
                               size_t stride_bytes, hsib_binding** out, char* error, size_t error_size);
HSIB_API hsib_status hsib_bind_ex(const hsib_sequence* sequence, const float* rest_xy, size_t vertex_count, size_t stride_bytes,
                                  const hsib_bind_options* options, hsib_binding** out, char* error, size_t error_size);
/* Binding flags (hsib_bind_flags; hsib_bind and hsib_bind_ex pass 0). */
#define HSIB_BIND_DERIVATIVES 1u /* also store each vertex's derivative rows (d row/dx, d row/dy): the
                                    binding takes 3x the memory and can report distortion */
/* hsib_bind_ex with flags; unknown bits are refused (HSIB_ERROR_ARGUMENT). Memory in
 * the caller's block: hsib_binding_memory_size_flags bytes. */
HSIB_API hsib_status hsib_bind_flags(const hsib_sequence* sequence, const float* rest_xy, size_t vertex_count, size_t stride_bytes,
                                     const hsib_bind_options* options, uint32_t flags, hsib_binding** out, char* error,
                                     size_t error_size);
HSIB_API void hsib_unbind(hsib_binding* binding);
HSIB_API size_t hsib_binding_vertex_count(const hsib_binding* binding);
HSIB_API const hsib_sequence* hsib_binding_sequence(const hsib_binding* binding);
HSIB_API size_t hsib_binding_bytes(const hsib_binding* binding);
/* Bytes a binding of vertex_count vertices takes (0 if that overflows). */
HSIB_API size_t hsib_binding_memory_size(const hsib_sequence* sequence, size_t vertex_count);
/* The same for a binding made with `flags` (0 for unknown bits or an overflow). */
HSIB_API size_t hsib_binding_memory_size_flags(const hsib_sequence* sequence, size_t vertex_count, uint32_t flags);
/* The flags the binding was made with (HSIB_BIND_DERIVATIVES: it can report distortion). */
HSIB_API uint32_t hsib_binding_flags(const hsib_binding* binding);

/* Writes frame `frame`'s deformed vertices (x, y floats at out_stride bytes apart,
 * 0 = packed). hsib_evaluate_range does vertices [first, first + count) only, so a
 * caller can split a mesh over its own worker threads. */
HSIB_API hsib_status hsib_evaluate(const hsib_binding* binding, uint32_t frame, float* out_xy, size_t out_stride_bytes);
HSIB_API hsib_status hsib_evaluate_range(const hsib_binding* binding, uint32_t frame, size_t first, size_t count,
                                         float* out_xy, size_t out_stride_bytes);
/* The same for a blend (hsib_blend_at_time): the blend of the two frames' weights. */
HSIB_API hsib_status hsib_evaluate_blend(const hsib_binding* binding, const hsib_blend* blend, float* out_xy, size_t out_stride_bytes);
HSIB_API hsib_status hsib_evaluate_blend_range(const hsib_binding* binding, const hsib_blend* blend, size_t first, size_t count,
                                               float* out_xy, size_t out_stride_bytes);

/* Distortion (see "Distortion" above; the binding needs HSIB_BIND_DERIVATIVES, else
 * HSIB_ERROR_ARGUMENT): per vertex sigma1, sigma2 (2 floats at out_stride bytes apart,
 * 0 = packed) of frame `frame` or of a blend, sampled at the vertex, not a bound. */
HSIB_API hsib_status hsib_evaluate_distortion(const hsib_binding* binding, uint32_t frame, float* out_sigma, size_t out_stride_bytes);
HSIB_API hsib_status hsib_evaluate_blend_distortion(const hsib_binding* binding, const hsib_blend* blend, float* out_sigma,
                                                    size_t out_stride_bytes);
HSIB_API hsib_status hsib_evaluate_blend_distortion_range(const hsib_binding* binding, const hsib_blend* blend, size_t first, size_t count,
                                                          float* out_sigma, size_t out_stride_bytes);
/* The Jacobian itself: per vertex df/dx then df/dy (a, c, b, d: column-major, as GLSL's
 * mat2; 4 floats at out_stride bytes apart, 0 = packed), of a blend (for a frame:
 * frame0 == frame1, s = 0). */
HSIB_API hsib_status hsib_evaluate_jacobian_range(const hsib_binding* binding, const hsib_blend* blend, size_t first, size_t count,
                                                  float* out_jacobian, size_t out_stride_bytes);
/* sigma1, sigma2 of a Jacobian given as hsib_evaluate_jacobian_range writes it. */
HSIB_API void hsib_singular_values(const float jacobian[4], float sigma[2]);

/* The frame's weights: 2R floats (w_x, w_y per row, rotation applied) and the
 * translation, for callers that run the product themselves (e.g. in a shader). */
HSIB_API hsib_status hsib_frame_weights(const hsib_sequence* sequence, uint32_t frame, float* weights,
                                        float translation[2]);
HSIB_API hsib_status hsib_blend_weights(const hsib_sequence* sequence, const hsib_blend* blend, float* weights,
                                        float translation[2]);
/* One vertex's basis row (R floats), as a binding stores it. */
HSIB_API hsib_status hsib_basis_row(const hsib_sequence* sequence, double x, double y, float* row);
/* The same row and its derivatives d row/dx, d row/dy (R floats each), as a binding
 * with HSIB_BIND_DERIVATIVES stores them. */
HSIB_API hsib_status hsib_basis_row_derivatives(const hsib_sequence* sequence, double x, double y, float* row, float* dx, float* dy);

/* GPU playback (hsi/hsib_playback.glsl): the data its vertex shader reads.
 * Rows: each vertex's R basis rows as T = ceil(R/4) RGBA32F texels (4 rows a texel,
 * zero-padded), texel v*T + q of an image `width` texels wide, line after line (or
 * a storage buffer of vec4 under Vulkan); hsib_gpu_rows_floats says how many floats
 * (4 * width * lines). Uniforms, per draw: 4 * (2 + R) floats, std140-compatible:
 * (c0.x, c0.y, c1.x, c1.y), (s, R, T, 0), then per row (w0.x, w0.y, w1.x, w1.y) of the
 * blend's two frames (hsib_blend_at_time), which the shader mixes with s.
 * Derivative rows (a binding with HSIB_BIND_DERIVATIVES; hsib_singular_values(vertex)
 * in the shader): 2T texels per vertex, texel 2(v*T + q) holds d/dx of rows
 * 4q..4q+3 and texel 2(v*T + q) + 1 their d/dy, in a second image or buffer laid out
 * as the rows are; the uniforms are the same. hsib_gpu_derivative_rows_floats is 0
 * (and hsib_gpu_derivative_rows HSIB_ERROR_ARGUMENT) for a binding without them. */
HSIB_API uint32_t hsib_gpu_texels_per_vertex(const hsib_sequence* sequence);
HSIB_API size_t hsib_gpu_rows_floats(const hsib_binding* binding, uint32_t width);
HSIB_API hsib_status hsib_gpu_rows(const hsib_binding* binding, uint32_t width, float* texels);
HSIB_API size_t hsib_gpu_derivative_rows_floats(const hsib_binding* binding, uint32_t width);
HSIB_API hsib_status hsib_gpu_derivative_rows(const hsib_binding* binding, uint32_t width, float* texels);
HSIB_API hsib_status hsib_gpu_uniforms(const hsib_sequence* sequence, const hsib_blend* blend, float* uniforms);

/* CRC-32 (IEEE) of bytes, as the format uses it. */
HSIB_API uint32_t hsib_crc32(const void* data, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* HSI_BAKED_RUNTIME_H */
