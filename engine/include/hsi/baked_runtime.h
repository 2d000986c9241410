/* Baked playback of an hsi sequence: a tiny, dependency-free C99 runtime (this header
 * and engine/src/baked_runtime.c, nothing else) that plays a .hsib file back on any
 * render mesh. It precomputes the mesh's basis rows once (Cauchy coordinates of the
 * cage and one log term per hole, math.md §2) and then makes each frame's vertices
 * with one small matrix product: vertex = rows(vertex) · W(frame) + translation.
 *
 * ---------------------------------------------------------------------------------
 * File format .hsib, version 1. All integers and floats little-endian, IEEE 754.
 *
 * Header (96 bytes):
 *    0  char[4]  magic "HSIB"
 *    4  u32      format version (1)
 *    8  u32      header size in bytes (96)
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
 *   92  u32      CRC-32 of header bytes 0..91
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
 * Frames (F records of S bytes each, then the end of the file):
 *    0  f64      time t
 *    8  u32      flags: 1 certified locally injective, 2 keyframe, 4 converged,
 *                8 overlaps itself (the image of the shape's boundary crosses
 *                itself at the sampled breakpoints: not globally injective)
 *   12  u32      reserved (0)
 *   16  f64[2]   rotation r (unit complex number)
 *   32  f64[2]   translation c
 *   48  D x f32|f64  reduced coefficients x (hsi's ModuloRigid gauge, math.md §3)
 *   S-4 u32      CRC-32 of the record's bytes 0..S-5
 * CRC-32 is the IEEE / zlib one (polynomial 0xEDB88320, initial and final xor ~0).
 *
 * A frame's map at a point w (any point inside the cage, not only on the shape) is
 *   f(w) = r * sum_k row_k(w) * (w[2k] + i w[2k+1]) + c,   w = E x,
 * where row_k(w) is the real basis function that row source k names. For the
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
 * Readers refuse, with a message naming the problem and the byte or frame: a wrong
 * magic, another version, a header or static-section checksum mismatch, impossible
 * sizes, a truncated file or trailing bytes, and a frame whose checksum fails.
 * ---------------------------------------------------------------------------------
 *
 * Thread safety: a sequence and a binding are immutable once made; any number of
 * threads may call hsib_evaluate / hsib_evaluate_range / the queries on them at
 * once. hsib_set_allocator must be called before anything else and is not
 * thread-safe. Memory: only what hsib_* allocates, through the allocator hooks.
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

#define HSIB_FORMAT_VERSION 1
#define HSIB_HEADER_SIZE 96

#define HSIB_FRAME_CERTIFIED 1u
#define HSIB_FRAME_KEYFRAME 2u
#define HSIB_FRAME_CONVERGED 4u
#define HSIB_FRAME_OVERLAPS 8u /* the frame overlaps itself (see the frame record) */

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
} hsib_info;

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
HSIB_API void hsib_close(hsib_sequence* sequence);

HSIB_API void hsib_get_info(const hsib_sequence* sequence, hsib_info* info);
HSIB_API hsib_status hsib_frame_info(const hsib_sequence* sequence, uint32_t frame, double* t, uint32_t* flags);
/* The frame whose time is nearest t (clamped to the sequence). */
HSIB_API uint32_t hsib_frame_at_time(const hsib_sequence* sequence, double t);

/* Precomputes the basis rows of vertex_count rest vertices (x, y floats; stride in
 * bytes between vertices, 0 = tightly packed). Every vertex must lie inside the
 * cage's outer loop and outside its hole loops (the shape and a margin around it);
 * otherwise HSIB_ERROR_DOMAIN names the first vertex that does not. The binding
 * refers to the sequence, which must outlive it. */
HSIB_API hsib_status hsib_bind(const hsib_sequence* sequence, const float* rest_xy, size_t vertex_count,
                               size_t stride_bytes, hsib_binding** out, char* error, size_t error_size);
HSIB_API void hsib_unbind(hsib_binding* binding);
HSIB_API size_t hsib_binding_vertex_count(const hsib_binding* binding);
HSIB_API size_t hsib_binding_bytes(const hsib_binding* binding);

/* Writes frame `frame`'s deformed vertices (x, y floats at out_stride bytes apart,
 * 0 = packed). hsib_evaluate_range does vertices [first, first + count) only, so a
 * caller can split a mesh over its own worker threads. */
HSIB_API hsib_status hsib_evaluate(const hsib_binding* binding, uint32_t frame, float* out_xy, size_t out_stride_bytes);
HSIB_API hsib_status hsib_evaluate_range(const hsib_binding* binding, uint32_t frame, size_t first, size_t count,
                                         float* out_xy, size_t out_stride_bytes);

/* The frame's weights: 2R floats (w_x, w_y per row, rotation applied) and the
 * translation, for callers that run the product themselves (e.g. in a shader). */
HSIB_API hsib_status hsib_frame_weights(const hsib_sequence* sequence, uint32_t frame, float* weights,
                                        float translation[2]);
/* One vertex's basis row (R floats), as a binding stores it. */
HSIB_API hsib_status hsib_basis_row(const hsib_sequence* sequence, double x, double y, float* row);

/* CRC-32 (IEEE) of bytes, as the format uses it. */
HSIB_API uint32_t hsib_crc32(const void* data, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* HSI_BAKED_RUNTIME_H */
