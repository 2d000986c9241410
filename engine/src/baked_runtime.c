/* The baked playback runtime (format and API in hsi/baked_runtime.h): C99, the C
 * library only. Reads are byte-by-byte little-endian, so it runs on any host. The
 * single-file hsib.h is generated from this file and the header (its static names
 * carry the hsib__ prefix so that they do not collide with the includer's). */
#include "hsi/baked_runtime.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Vertices are processed in panels of this many: a panel's rows are stored row by
 * row (R x PANEL floats), so a frame is, per panel, R axpy's of PANEL floats into
 * two accumulators that stay in L1 and vectorise. */
#define HSIB_PANEL 64

#define HSIB_PI 3.14159265358979323846

/* ---------------------------------------------------------------- allocation */

static void* hsib__default_allocate(size_t bytes, void* user) {
  (void)user;
  return malloc(bytes);
}
static void hsib__default_release(void* p, void* user) {
  (void)user;
  free(p);
}
static hsib_allocator hsib__g_alloc = {hsib__default_allocate, hsib__default_release, NULL};

void hsib_set_allocator(const hsib_allocator* allocator) {
  if (allocator && allocator->allocate && allocator->release)
    hsib__g_alloc = *allocator;
  else {
    hsib__g_alloc.allocate = hsib__default_allocate;
    hsib__g_alloc.release = hsib__default_release;
    hsib__g_alloc.user = NULL;
  }
}

static void* hsib_alloc(size_t bytes) { return hsib__g_alloc.allocate(bytes ? bytes : 1, hsib__g_alloc.user); }
static void hsib_free(void* p) {
  if (p) hsib__g_alloc.release(p, hsib__g_alloc.user);
}

/* ---------------------------------------------------------------- errors */

const char* hsib_status_name(hsib_status s) {
  switch (s) {
    case HSIB_OK: return "ok";
    case HSIB_ERROR_ARGUMENT: return "invalid argument";
    case HSIB_ERROR_IO: return "I/O error";
    case HSIB_ERROR_FORMAT: return "not a valid baked sequence";
    case HSIB_ERROR_VERSION: return "unsupported format version";
    case HSIB_ERROR_TRUNCATED: return "truncated file";
    case HSIB_ERROR_CHECKSUM: return "checksum mismatch";
    case HSIB_ERROR_MEMORY: return "out of memory";
    case HSIB_ERROR_DOMAIN: return "vertex outside the cage";
  }
  return "unknown status";
}

const char* hsib_stop_name(uint32_t stop) {
  switch (stop) {
    case HSIB_STOP_CONVERGED: return "converged";
    case HSIB_STOP_ITERATION_LIMIT: return "iteration limit";
    case HSIB_STOP_STAGNATED: return "stagnated";
    case HSIB_STOP_CERTIFICATE_REFUSED: return "certificate refused";
    case HSIB_STOP_NO_DECREASE: return "no decrease";
    case HSIB_STOP_NOT_FACTORED: return "not factored";
    case HSIB_STOP_START_FOLDS: return "start folds";
    case HSIB_STOP_START_NOT_CERTIFIED: return "start not certified";
    case HSIB_STOP_NOT_RECORDED: return "not recorded";
    default: return "unknown";
  }
}

static hsib_status hsib__fail(char* error, size_t error_size, hsib_status s, const char* fmt, ...) {
  if (error && error_size) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(error, error_size, fmt, ap);
    va_end(ap);
  }
  return s;
}

/* ---------------------------------------------------------------- CRC-32 */

uint32_t hsib_crc32(const void* data, size_t size) {
  uint32_t table[256];
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  const unsigned char* p = (const unsigned char*)data;
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

/* ---------------------------------------------------------------- little-endian reads */

static uint32_t hsib__rd_u32(const unsigned char* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t hsib__rd_u64(const unsigned char* p) { return (uint64_t)hsib__rd_u32(p) | ((uint64_t)hsib__rd_u32(p + 4) << 32); }
static double hsib__rd_f64(const unsigned char* p) {
  const uint64_t u = hsib__rd_u64(p);
  double d;
  memcpy(&d, &u, 8);
  return d;
}
static float hsib__rd_f32(const unsigned char* p) {
  const uint32_t u = hsib__rd_u32(p);
  float f;
  memcpy(&f, &u, 4);
  return f;
}

/* ---------------------------------------------------------------- the sequence */

typedef struct hsib_entry {
  uint32_t target, source;
  double value;
} hsib_entry;

/* A sequence is one block: this struct, then its arrays (16-byte aligned), so that
 * it can live in memory the caller gives (hsib_open_in_place). */
struct hsib_sequence {
  hsib_info info;
  uint32_t* loop_sizes;    /* L */
  double* cage;            /* m x 2 */
  double* holes;           /* N x 2 */
  uint32_t* rows;          /* R row sources */
  hsib_entry* expansion;   /* Z */
  uint32_t* shape_sizes;   /* Ls vertices per shape loop (version 2) */
  double* shape;           /* Ms x 2 */
  float* mesh_xy;          /* P x 2 rest vertices */
  float* mesh_uv;          /* P x 2 texture coordinates */
  uint32_t* triangles;     /* T x 3 */
  double texture_rect[4];
  uint32_t Z, frame_bytes;
  unsigned char* frames;   /* F x frame_bytes, as in the file */
  int caller_memory;       /* the block is the caller's: hsib_close releases nothing */
};

void hsib_close(hsib_sequence* s) {
  if (s && !s->caller_memory) hsib_free(s);
}

#define HSIB_LIMIT_LOOPS 100000u
#define HSIB_LIMIT_VERTICES 10000000u
#define HSIB_LIMIT_MESH 100000000u

/* What the header announces, checked for consistency. */
typedef struct hsib_layout {
  uint32_t version, header_bytes, flags, L, m, N, R, D, Z, F, S, k, P, T, Ls, Ms;
  uint64_t static_bytes, total_bytes;
  size_t block_bytes;  /* the sequence's one allocation */
} hsib_layout;

static size_t hsib__align16(size_t n) { return (n + 15u) & ~(size_t)15u; }

/* The block: struct, then each array rounded up to 16 bytes. Also used to carve it. */
static uint64_t hsib__block_size(const hsib_layout* y) {
  const uint64_t parts[] = {sizeof(hsib_sequence), 4ull * y->L, 16ull * y->m, 16ull * y->N, 4ull * y->R, sizeof(hsib_entry) * (uint64_t)y->Z,
                            4ull * y->Ls, 16ull * y->Ms, 8ull * y->P, 8ull * y->P, 12ull * y->T, (uint64_t)y->F * y->S};
  uint64_t total = 0;
  for (size_t i = 0; i < sizeof parts / sizeof parts[0]; ++i) total += (parts[i] + 15u) & ~(uint64_t)15u;
  return total;
}

static hsib_status hsib__read_header(const unsigned char* b, size_t size, hsib_layout* y, char* error, size_t es) {
  memset(y, 0, sizeof *y);
  if (!b && size) return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "the file's bytes are NULL");
  if (size < 4) return hsib__fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %d", size, HSIB_HEADER_SIZE_V1);
  if (memcmp(b, "HSIB", 4) != 0) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "not an hsi baked sequence (magic is not \"HSIB\")");
  if (size < 8) return hsib__fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %d", size, HSIB_HEADER_SIZE_V1);
  const uint32_t version = hsib__rd_u32(b + 4);
  if (version != 1u && version != HSIB_FORMAT_VERSION)
    return hsib__fail(error, es, HSIB_ERROR_VERSION, "unsupported baked format version %u (this runtime reads versions 1 and %d)", version,
                HSIB_FORMAT_VERSION);
  const uint32_t H = version == 1u ? HSIB_HEADER_SIZE_V1 : HSIB_HEADER_SIZE;
  if (size < H) return hsib__fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %u", size, H);
  if (hsib__rd_u32(b + H - 4) != hsib_crc32(b, H - 4))
    return hsib__fail(error, es, HSIB_ERROR_CHECKSUM, "header checksum mismatch (bytes 0..%u): the file is corrupt", H - 5);
  if (hsib__rd_u32(b + 8) != H) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "header size %u, version %u has %u", hsib__rd_u32(b + 8), version, H);
  y->version = version;
  y->header_bytes = H;
  y->flags = hsib__rd_u32(b + 12);
  if (y->flags > 1u) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "unknown header flags 0x%x (at byte 12)", y->flags);
  y->L = hsib__rd_u32(b + 16), y->m = hsib__rd_u32(b + 20), y->N = hsib__rd_u32(b + 24), y->R = hsib__rd_u32(b + 28), y->D = hsib__rd_u32(b + 32);
  y->Z = hsib__rd_u32(b + 36), y->F = hsib__rd_u32(b + 40), y->S = hsib__rd_u32(b + 44);
  y->static_bytes = hsib__rd_u64(b + 80);
  if (version >= 2u) {
    y->k = hsib__rd_u32(b + 92), y->P = hsib__rd_u32(b + 96), y->T = hsib__rd_u32(b + 100), y->Ls = hsib__rd_u32(b + 104), y->Ms = hsib__rd_u32(b + 108);
    for (uint32_t at = 112; at < H - 4; at += 4)
      if (hsib__rd_u32(b + at) != 0) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "reserved header field is not 0 (at byte %u)", at);
  }
  if (y->L < 1 || y->L > HSIB_LIMIT_LOOPS) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible cage loop count %u (at byte 16)", y->L);
  if (y->m < 3 * y->L || y->m > HSIB_LIMIT_VERTICES)
    return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible cage vertex count %u for %u loops (at byte 20)", y->m, y->L);
  if (y->N != y->L - 1) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "hole count %u does not match %u hole loops (at byte 24)", y->N, y->L - 1);
  if (y->R < 1 || y->R > 2 * y->m + y->N) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible basis row length %u (at byte 28)", y->R);
  if (y->D < 1 || y->D > 4 * (y->m + y->N)) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible coefficient count %u (at byte 32)", y->D);
  if (y->Z > 8u * y->D) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible expansion size %u (at byte 36)", y->Z);
  if (version >= 2u) {
    if (y->k > 1000000u) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible blend sub-step count %u (at byte 92)", y->k);
    if (y->P > HSIB_LIMIT_MESH || (y->P == 0) != (y->T == 0) || y->T > HSIB_LIMIT_MESH)
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible mesh of %u vertices and %u triangles (at byte 96)", y->P, y->T);
    if (y->Ls > HSIB_LIMIT_LOOPS || y->Ms > HSIB_LIMIT_VERTICES || (y->Ls > 0 && y->Ms < 3 * y->Ls) || (y->Ls == 0) != (y->Ms == 0))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "impossible shape of %u loops and %u vertices (at byte 104)", y->Ls, y->Ms);
  }
  const uint32_t scalar = (y->flags & 1u) ? 4u : 8u;
  const uint64_t want_S = 48u + (uint64_t)y->D * scalar + 4u;
  if (y->S != want_S)
    return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame record size %u, the header's sizes give %llu (at byte 44)", y->S, (unsigned long long)want_S);
  uint64_t want_static = 4ull * y->L + 16ull * y->m + 16ull * y->N + 4ull * y->R + 16ull * y->Z;
  if (version >= 2u) want_static += 4ull * y->Ls + 16ull * y->Ms + 32ull + 8ull * y->P + 12ull * y->T;
  if (y->static_bytes != want_static)
    return hsib__fail(error, es, HSIB_ERROR_FORMAT, "static section size %llu, the header's sizes give %llu (at byte 80)",
                (unsigned long long)y->static_bytes, (unsigned long long)want_static);
  y->total_bytes = H + want_static + (uint64_t)y->F * y->S;
  /* Before anything is allocated: the memory a sequence takes is bounded by its file's size. */
  if ((uint64_t)size < y->total_bytes)
    return hsib__fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: the file has %zu bytes, its header announces %llu (%u frames)", size,
                      (unsigned long long)y->total_bytes, y->F);
  if ((uint64_t)size > y->total_bytes)
    return hsib__fail(error, es, HSIB_ERROR_TRUNCATED, "%llu trailing bytes after the last of %u frames",
                      (unsigned long long)(size - y->total_bytes), y->F);
  const uint64_t block = hsib__block_size(y);
  if (block > (uint64_t)(size_t)-1 / 2) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "the header announces %llu bytes", (unsigned long long)block);
  y->block_bytes = (size_t)block;
  return HSIB_OK;
}

static hsib_status hsib__parse(const unsigned char* b, size_t size, const hsib_layout* y, hsib_sequence* s, char* error, size_t es) {
  const uint32_t L = y->L, m = y->m, N = y->N, R = y->R, D = y->D, Z = y->Z, F = y->F, S = y->S;
  const unsigned char* st = b + y->header_bytes;
  if (hsib__rd_u32(b + 88) != hsib_crc32(st, (size_t)y->static_bytes))
    return hsib__fail(error, es, HSIB_ERROR_CHECKSUM, "static section checksum mismatch (bytes %u..%llu): the file is corrupt", y->header_bytes,
                (unsigned long long)(y->header_bytes + y->static_bytes - 1));

  /* Carve the block (the same rounding as block_size). */
  unsigned char* at = (unsigned char*)s + hsib__align16(sizeof *s);
#define HSIB_CARVE(field, type, count) \
  do {                                 \
    s->field = (type*)(void*)at;       \
    at += hsib__align16(sizeof(type) * (size_t)(count)); \
  } while (0)
  HSIB_CARVE(loop_sizes, uint32_t, L);
  HSIB_CARVE(cage, double, 2 * (size_t)m);
  HSIB_CARVE(holes, double, 2 * (size_t)N);
  HSIB_CARVE(rows, uint32_t, R);
  HSIB_CARVE(expansion, hsib_entry, Z);
  HSIB_CARVE(shape_sizes, uint32_t, y->Ls);
  HSIB_CARVE(shape, double, 2 * (size_t)y->Ms);
  HSIB_CARVE(mesh_xy, float, 2 * (size_t)y->P);
  HSIB_CARVE(mesh_uv, float, 2 * (size_t)y->P);
  HSIB_CARVE(triangles, uint32_t, 3 * (size_t)y->T);
  HSIB_CARVE(frames, unsigned char, (size_t)F * S);
#undef HSIB_CARVE

  hsib_info* in = &s->info;
  in->version = y->version;
  in->frame_count = F;
  in->loop_count = L;
  in->cage_vertex_count = m;
  in->hole_count = N;
  in->row_length = R;
  in->coefficient_count = D;
  in->single_precision = (int)(y->flags & 1u);
  for (int k = 0; k < 4; ++k) in->bbox[k] = hsib__rd_f64(b + 48 + 8 * k);
  in->file_bytes = size;
  in->blend_substeps = y->k;
  in->mesh_vertex_count = y->P;
  in->mesh_triangle_count = y->T;
  in->shape_loop_count = y->Ls;
  in->sequence_bytes = y->block_bytes;
  s->Z = Z;
  s->frame_bytes = S;

  const unsigned char* p = st;
  uint64_t msum = 0;
  for (uint32_t l = 0; l < L; ++l, p += 4) {
    s->loop_sizes[l] = hsib__rd_u32(p);
    if (s->loop_sizes[l] < 3)
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "cage loop %u has %u vertices (at byte %ld)", l, s->loop_sizes[l], (long)(p - b));
    msum += s->loop_sizes[l];
  }
  if (msum != m) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "cage loop sizes sum to %llu, the header says %u", (unsigned long long)msum, m);
  for (uint32_t j = 0; j < 2 * m; ++j, p += 8) {
    s->cage[j] = hsib__rd_f64(p);
    if (!isfinite(s->cage[j])) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "non-finite cage vertex %u (at byte %ld)", j / 2, (long)(p - b));
  }
  for (uint32_t j = 0; j < 2 * N; ++j, p += 8) {
    s->holes[j] = hsib__rd_f64(p);
    if (!isfinite(s->holes[j])) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "non-finite hole point %u (at byte %ld)", j / 2, (long)(p - b));
  }
  for (uint32_t r = 0; r < R; ++r, p += 4) {
    const uint32_t src = hsib__rd_u32(p), part = src & 3u, col = src >> 2;
    if (part == 3u || (part < 2u && col >= m) || (part == 2u && col >= N))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "row source %u names column %u part %u, which does not exist (at byte %ld)", r, col, part,
                  (long)(p - b));
    s->rows[r] = src;
  }
  for (uint32_t z = 0; z < Z; ++z, p += 16) {
    hsib_entry* e = &s->expansion[z];
    e->target = hsib__rd_u32(p);
    e->source = hsib__rd_u32(p + 4);
    e->value = hsib__rd_f64(p + 8);
    if (e->target >= 2 * R || e->source >= D || !isfinite(e->value))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "expansion entry %u (%u, %u) is out of range (at byte %ld)", z, e->target, e->source,
                  (long)(p - b));
  }
  if (y->version >= 2u) {
    msum = 0;
    for (uint32_t l = 0; l < y->Ls; ++l, p += 4) {
      s->shape_sizes[l] = hsib__rd_u32(p);
      if (s->shape_sizes[l] < 3)
        return hsib__fail(error, es, HSIB_ERROR_FORMAT, "shape loop %u has %u vertices (at byte %ld)", l, s->shape_sizes[l], (long)(p - b));
      msum += s->shape_sizes[l];
    }
    if (msum != y->Ms)
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "shape loop sizes sum to %llu, the header says %u", (unsigned long long)msum, y->Ms);
    for (uint32_t j = 0; j < 2 * y->Ms; ++j, p += 8) {
      s->shape[j] = hsib__rd_f64(p);
      if (!isfinite(s->shape[j])) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "non-finite shape vertex %u (at byte %ld)", j / 2, (long)(p - b));
    }
    for (int k = 0; k < 4; ++k, p += 8) s->texture_rect[k] = hsib__rd_f64(p);
    if (!isfinite(s->texture_rect[0]) || !isfinite(s->texture_rect[1]) || !isfinite(s->texture_rect[2]) || !isfinite(s->texture_rect[3]) ||
        !(s->texture_rect[2] > s->texture_rect[0]) || !(s->texture_rect[3] > s->texture_rect[1]))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "the texture rectangle is empty or not finite (at byte %ld)", (long)(p - 32 - b));
    const double* r = s->texture_rect;
    for (uint32_t v = 0; v < y->P; ++v, p += 8) {
      const float x = hsib__rd_f32(p), yy = hsib__rd_f32(p + 4);
      if (!isfinite(x) || !isfinite(yy)) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "mesh vertex %u is not finite (at byte %ld)", v, (long)(p - b));
      s->mesh_xy[2 * v] = x;
      s->mesh_xy[2 * v + 1] = yy;
      s->mesh_uv[2 * v] = (float)((x - r[0]) / (r[2] - r[0]));
      s->mesh_uv[2 * v + 1] = (float)((r[3] - yy) / (r[3] - r[1]));
    }
    for (uint32_t t = 0; t < 3 * y->T; ++t, p += 4) {
      s->triangles[t] = hsib__rd_u32(p);
      if (s->triangles[t] >= y->P)
        return hsib__fail(error, es, HSIB_ERROR_FORMAT, "triangle %u names vertex %u of %u (at byte %ld)", t / 3, s->triangles[t], y->P, (long)(p - b));
    }
  }
  memcpy(s->frames, p, (size_t)F * S);
  const uint32_t scalar = (y->flags & 1u) ? 4u : 8u;
  const uint32_t known_flags = y->version >= 2u ? 63u : 15u;
  for (uint32_t f = 0; f < F; ++f) {
    const unsigned char* fr = s->frames + (size_t)f * S;
    const long at_f = (long)(p - b) + (long)((size_t)f * S);
    if (hsib__rd_u32(fr + S - 4) != hsib_crc32(fr, S - 4))
      return hsib__fail(error, es, HSIB_ERROR_CHECKSUM, "frame %u checksum mismatch (record at byte %ld): the file is corrupt", f, at_f);
    const double t = hsib__rd_f64(fr);
    const uint32_t ff = hsib__rd_u32(fr + 8);
    if (!isfinite(t) || (f > 0 && !(t >= hsib__rd_f64(fr - S))))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: time is not finite or decreases (at byte %ld)", f, at_f);
    if (ff > known_flags) return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: unknown flags 0x%x (at byte %ld)", f, ff, at_f + 8);
    if ((ff & (HSIB_FRAME_BLEND_CERTIFIED | HSIB_FRAME_BLEND_OVERLAPS)) && (f + 1 == F || y->k < 2u))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: blend flags without a next frame or sub-steps (at byte %ld)", f, at_f + 8);
    /* The stop word: 0 (not recorded) or 0x100 | an HSIB_STOP_* code, 0 exactly with flag 4. */
    const uint32_t sw = hsib__rd_u32(fr + 12);
    if (sw != 0u && ((sw & ~0x1FFu) != 0u || (sw & 0x100u) == 0u))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: unknown stop word 0x%x (at byte %ld)", f, sw, at_f + 12);
    if (sw != 0u) {
      const uint32_t code = sw & 0xFFu;
      if (code >= HSIB_STOP_COUNT)
        return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: unknown stop code %u (at byte %ld)", f, code, at_f + 12);
      if ((code == HSIB_STOP_CONVERGED) != ((ff & HSIB_FRAME_CONVERGED) != 0u))
        return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: stop code %u (%s) contradicts the converged flag 4 (at byte %ld)", f, code,
                          hsib_stop_name(code), at_f + 12);
    }
    const double rr = hsib__rd_f64(fr + 16), ri = hsib__rd_f64(fr + 24);
    if (!isfinite(rr) || !isfinite(ri) || fabs(hypot(rr, ri) - 1.0) > 1e-6 || !isfinite(hsib__rd_f64(fr + 32)) || !isfinite(hsib__rd_f64(fr + 40)))
      return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: the pose is not a rotation and a finite translation (at byte %ld)", f, at_f + 16);
    for (uint32_t d = 0; d < D; ++d) {
      const unsigned char* q = fr + 48 + (size_t)d * scalar;
      const double x = scalar == 4 ? (double)hsib__rd_f32(q) : hsib__rd_f64(q);
      if (!isfinite(x))
        return hsib__fail(error, es, HSIB_ERROR_FORMAT, "frame %u: coefficient %u is not finite (at byte %ld)", f, d, at_f + 48 + (long)(d * scalar));
    }
  }
  in->t_begin = F ? hsib__rd_f64(s->frames) : 0.0;
  in->t_end = F ? hsib__rd_f64(s->frames + (size_t)(F - 1) * S) : 0.0;
  return HSIB_OK;
}

hsib_status hsib_sequence_bytes(const void* data, size_t size, size_t* bytes, char* error, size_t error_size) {
  if (error && error_size) error[0] = '\0';
  if (!bytes) return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_sequence_bytes: bytes is NULL");
  *bytes = 0;
  hsib_layout y;
  const hsib_status st = hsib__read_header((const unsigned char*)data, size, &y, error, error_size);
  if (st == HSIB_OK) *bytes = y.block_bytes;
  return st;
}

static hsib_status hsib__open_into(const void* data, size_t size, void* memory, size_t memory_bytes, hsib_sequence** out, char* error,
                             size_t error_size) {
  if (error && error_size) error[0] = '\0';
  if (!out) return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open: out is NULL");
  *out = NULL;
  if (!data && size) return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open: data is NULL");
  hsib_layout y;
  hsib_status st = hsib__read_header((const unsigned char*)data, size, &y, error, error_size);
  if (st != HSIB_OK) return st;
  hsib_sequence* s;
  if (memory) {
    if (((uintptr_t)memory & 15u) != 0)
      return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_in_place: the memory is not 16-byte aligned");
    if (memory_bytes < y.block_bytes)
      return hsib__fail(error, error_size, HSIB_ERROR_MEMORY, "hsib_open_in_place: %zu bytes given, the sequence needs %zu (hsib_sequence_bytes)",
                  memory_bytes, y.block_bytes);
    s = (hsib_sequence*)memory;
  } else {
    s = (hsib_sequence*)hsib_alloc(y.block_bytes);
    if (!s) return hsib__fail(error, error_size, HSIB_ERROR_MEMORY, "out of memory (%zu bytes) reading a sequence of %u frames", y.block_bytes, y.F);
  }
  memset(s, 0, sizeof *s);
  s->caller_memory = memory != NULL;
  st = hsib__parse((const unsigned char*)data, size, &y, s, error, error_size);
  if (st != HSIB_OK) {
    hsib_close(s);
    return st;
  }
  *out = s;
  return HSIB_OK;
}

hsib_status hsib_open_memory(const void* data, size_t size, hsib_sequence** out, char* error, size_t error_size) {
  return hsib__open_into(data, size, NULL, 0, out, error, error_size);
}

hsib_status hsib_open_in_place(const void* data, size_t size, void* memory, size_t memory_bytes, hsib_sequence** out, char* error,
                               size_t error_size) {
  if (!memory) {
    if (error && error_size) error[0] = '\0';
    if (out) *out = NULL;
    return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_in_place: memory is NULL");
  }
  return hsib__open_into(data, size, memory, memory_bytes, out, error, error_size);
}

hsib_status hsib_open_file(const char* path, hsib_sequence** out, char* error, size_t error_size) {
  if (error && error_size) error[0] = '\0';
  if (!out || !path) return hsib__fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_file: path or out is NULL");
  *out = NULL;
  FILE* f = fopen(path, "rb");
  if (!f) return hsib__fail(error, error_size, HSIB_ERROR_IO, "%s: cannot open the baked sequence", path);
  unsigned char* buf = NULL;
  size_t size = 0, cap = 0;
  for (;;) {
    if (size == cap) {
      cap = cap ? 2 * cap : 65536;
      unsigned char* nb = (unsigned char*)hsib_alloc(cap);
      if (!nb) {
        hsib_free(buf);
        fclose(f);
        return hsib__fail(error, error_size, HSIB_ERROR_MEMORY, "%s: out of memory reading the file", path);
      }
      if (buf) memcpy(nb, buf, size);
      hsib_free(buf);
      buf = nb;
    }
    const size_t got = fread(buf + size, 1, cap - size, f);
    size += got;
    if (got == 0) break;
  }
  const int read_error = ferror(f);
  fclose(f);
  if (read_error) {
    hsib_free(buf);
    return hsib__fail(error, error_size, HSIB_ERROR_IO, "%s: read error", path);
  }
  char inner[256] = {0};
  const hsib_status st = hsib_open_memory(buf, size, out, inner, sizeof inner);
  hsib_free(buf);
  if (st != HSIB_OK) return hsib__fail(error, error_size, st, "%s: %s", path, inner);
  return HSIB_OK;
}

void hsib_get_info(const hsib_sequence* s, hsib_info* info) {
  if (!info) return;
  if (!s) {
    memset(info, 0, sizeof *info);
    return;
  }
  *info = s->info;
}

hsib_status hsib_get_mesh(const hsib_sequence* s, hsib_mesh* mesh) {
  if (!mesh) return HSIB_ERROR_ARGUMENT;
  memset(mesh, 0, sizeof *mesh);
  if (!s) return HSIB_ERROR_ARGUMENT;
  if (s->info.mesh_vertex_count == 0) return HSIB_ERROR_VERSION;  /* version 1 files carry no mesh */
  mesh->vertex_count = s->info.mesh_vertex_count;
  mesh->triangle_count = s->info.mesh_triangle_count;
  mesh->xy = s->mesh_xy;
  mesh->uv = s->mesh_uv;
  mesh->triangles = s->triangles;
  memcpy(mesh->texture_rect, s->texture_rect, sizeof s->texture_rect);
  return HSIB_OK;
}

static const unsigned char* hsib__frame_record(const hsib_sequence* s, uint32_t f) { return s->frames + (size_t)f * s->frame_bytes; }
static double hsib__frame_time(const hsib_sequence* s, uint32_t f) { return hsib__rd_f64(hsib__frame_record(s, f)); }
static uint32_t hsib__frame_flags(const hsib_sequence* s, uint32_t f) { return hsib__rd_u32(hsib__frame_record(s, f) + 8); }

hsib_status hsib_frame_info(const hsib_sequence* s, uint32_t frame, double* t, uint32_t* flags) {
  if (!s || frame >= s->info.frame_count) return HSIB_ERROR_ARGUMENT;
  if (t) *t = hsib__frame_time(s, frame);
  if (flags) *flags = hsib__frame_flags(s, frame);
  return HSIB_OK;
}

hsib_status hsib_frame_stop(const hsib_sequence* s, uint32_t frame, uint32_t* stop) {
  if (!s || frame >= s->info.frame_count || !stop) return HSIB_ERROR_ARGUMENT;
  const uint32_t sw = hsib__rd_u32(hsib__frame_record(s, frame) + 12);  /* checked at open */
  if (sw != 0u)
    *stop = sw & 0xFFu;
  else
    *stop = (hsib__frame_flags(s, frame) & HSIB_FRAME_CONVERGED) ? HSIB_STOP_CONVERGED : HSIB_STOP_NOT_RECORDED;
  return HSIB_OK;
}

/* The last frame whose time is <= t (0 when t precedes them all). */
static uint32_t hsib__frame_before(const hsib_sequence* s, double t) {
  uint32_t lo = 0, hi = s->info.frame_count - 1;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo + 1) / 2;
    if (hsib__frame_time(s, mid) <= t) lo = mid; else hi = mid - 1;
  }
  return lo;
}

uint32_t hsib_frame_at_time(const hsib_sequence* s, double t) {
  if (!s || s->info.frame_count == 0) return 0;
  uint32_t lo = 0, hi = s->info.frame_count - 1;
  while (lo < hi) {  /* first frame with time >= t */
    const uint32_t mid = lo + (hi - lo) / 2;
    if (hsib__frame_time(s, mid) < t) lo = mid + 1; else hi = mid;
  }
  if (lo > 0 && fabs(hsib__frame_time(s, lo - 1) - t) <= fabs(hsib__frame_time(s, lo) - t)) --lo;
  return lo;
}

/* The one place that decides what is shown at time t: a blend only inside an interval
 * whose sub-steps the baker certified, else the nearest frame. */
hsib_blend hsib_blend_at_time(const hsib_sequence* s, double t, hsib_playback mode) {
  hsib_blend b = {0, 0, 0.0f, 0};
  if (!s || s->info.frame_count == 0) return b;
  const uint32_t nearest = hsib_frame_at_time(s, t);
  b.frame0 = b.frame1 = nearest;
  b.flags = hsib__frame_flags(s, nearest) & (HSIB_FRAME_CERTIFIED | HSIB_FRAME_KEYFRAME | HSIB_FRAME_CONVERGED | HSIB_FRAME_OVERLAPS);
  const uint32_t k = s->info.blend_substeps;
  if (mode == HSIB_PLAY_NEAREST || k < 2u || !isfinite(t)) return b;
  const uint32_t i = hsib__frame_before(s, t);
  if (i + 1 >= s->info.frame_count) return b;
  const uint32_t fi = hsib__frame_flags(s, i);
  const double t0 = hsib__frame_time(s, i), t1 = hsib__frame_time(s, i + 1);
  if (!(fi & HSIB_FRAME_BLEND_CERTIFIED) || !(t1 > t0)) return b;
  double u = (t - t0) / (t1 - t0);
  u = u < 0 ? 0 : (u > 1 ? 1 : u);
  const double j = floor(u * k + 0.5);  /* the nearest certified sub-step */
  if (mode == HSIB_PLAY_CERTIFIED_STEPS) u = j / k;
  if (u <= 0.0 || u >= 1.0) {  /* a frame itself */
    b.frame0 = b.frame1 = u <= 0.0 ? i : i + 1;
    b.flags = hsib__frame_flags(s, b.frame0) & (HSIB_FRAME_CERTIFIED | HSIB_FRAME_KEYFRAME | HSIB_FRAME_CONVERGED | HSIB_FRAME_OVERLAPS);
    return b;
  }
  b.frame0 = i;
  b.frame1 = i + 1;
  b.s = (float)u;
  /* Certified only at the sub-steps the baker certified; between them the blend is
   * a harmonic map that was not checked. */
  b.flags = HSIB_BLEND_BLENDED;
  if (u == j / k) b.flags |= HSIB_FRAME_CERTIFIED;
  if (fi & HSIB_FRAME_BLEND_OVERLAPS) b.flags |= HSIB_FRAME_OVERLAPS;
  return b;
}

/* w = r · (E x) as doubles (2R), plus the translation. */
static void hsib__frame_weights(const hsib_sequence* s, uint32_t frame, double* w, double c[2]) {
  const unsigned char* fr = hsib__frame_record(s, frame);
  const uint32_t R = s->info.row_length;
  const int single = s->info.single_precision;
  memset(w, 0, sizeof(double) * 2 * R);
  for (uint32_t z = 0; z < s->Z; ++z) {
    const hsib_entry* e = &s->expansion[z];
    const unsigned char* q = fr + 48 + (size_t)e->source * (single ? 4u : 8u);
    w[e->target] += e->value * (single ? (double)hsib__rd_f32(q) : hsib__rd_f64(q));
  }
  const double rr = hsib__rd_f64(fr + 16), ri = hsib__rd_f64(fr + 24);
  for (uint32_t k = 0; k < R; ++k) {
    const double a = w[2 * k], b = w[2 * k + 1];
    w[2 * k] = rr * a - ri * b;
    w[2 * k + 1] = rr * b + ri * a;
  }
  c[0] = hsib__rd_f64(fr + 32);
  c[1] = hsib__rd_f64(fr + 40);
}

static int hsib__blend_valid(const hsib_sequence* s, const hsib_blend* b) {
  return s && b && b->frame0 < s->info.frame_count && b->frame1 < s->info.frame_count && isfinite(b->s) && b->s >= 0.0f && b->s <= 1.0f;
}

/* The blended weights (1 − s) w0 + s w1 into wf (floats), w scratch of 4R doubles. */
static void hsib__blend_weights(const hsib_sequence* s, const hsib_blend* b, double* w, float* wf, double c[2]) {
  const uint32_t R = s->info.row_length;
  hsib__frame_weights(s, b->frame0, w, c);
  if (b->frame1 != b->frame0 && b->s != 0.0f) {
    double c1[2];
    const double u = b->s;
    hsib__frame_weights(s, b->frame1, w + 2 * (size_t)R, c1);
    for (uint32_t k = 0; k < 2 * R; ++k) w[k] = (1 - u) * w[k] + u * w[2 * (size_t)R + k];
    c[0] = (1 - u) * c[0] + u * c1[0];
    c[1] = (1 - u) * c[1] + u * c1[1];
  }
  for (uint32_t k = 0; k < 2 * R; ++k) wf[k] = (float)w[k];
}

hsib_status hsib_blend_weights(const hsib_sequence* s, const hsib_blend* b, float* weights, float translation[2]) {
  if (!hsib__blend_valid(s, b) || !weights) return HSIB_ERROR_ARGUMENT;
  double* w = (double*)hsib_alloc(sizeof(double) * 4 * s->info.row_length);
  if (!w) return HSIB_ERROR_MEMORY;
  double c[2];
  hsib__blend_weights(s, b, w, weights, c);
  if (translation) {
    translation[0] = (float)c[0];
    translation[1] = (float)c[1];
  }
  hsib_free(w);
  return HSIB_OK;
}

hsib_status hsib_frame_weights(const hsib_sequence* s, uint32_t frame, float* weights, float translation[2]) {
  const hsib_blend b = {frame, frame, 0.0f, 0};
  return hsib_blend_weights(s, &b, weights, translation);
}

/* ---------------------------------------------------------------- basis rows */

/* Cauchy coordinates of every cage vertex at w (the formula in hsi/baked_runtime.h; engine/src/basis.cpp is
 * the reference): C_j = 1/(2πi) [B_{j+1}/A_{j+1} log(B_{j+1}/B_j) − B_{j−1}/A_j log(B_j/B_{j−1})],
 * written out in real arithmetic. C has 2m doubles (re, im). When D is not NULL it
 * gets (2m doubles) the derivatives C_j'(w) = 1/(2πi) [L_{j−1}/A_j − L_j/A_{j+1}],
 * L_j = log(B_{j+1}/B_j) (basis.cpp's D): the B_{j±1} factors cancel against
 * d/dw L = 1/B_j − 1/B_{j+1}, which leaves only the logs. */
static void hsib__cauchy_coordinates(const hsib_sequence* s, double wx, double wy, double* C, double* D, double* scratch) {
  const double* z = s->cage;
  uint32_t off = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) {
    const uint32_t k = s->loop_sizes[l];
    double* B = scratch;       /* 2k: z_j − w */
    double* Lg = scratch + 2 * (size_t)k; /* 2k: log(B_{j+1}/B_j) */
    for (uint32_t j = 0; j < k; ++j) {
      B[2 * j] = z[2 * (off + j)] - wx;
      B[2 * j + 1] = z[2 * (off + j) + 1] - wy;
    }
    for (uint32_t j = 0; j < k; ++j) {
      const uint32_t jp = (j + 1) % k;
      const double ar = B[2 * j], ai = B[2 * j + 1], br = B[2 * jp], bi = B[2 * jp + 1];
      /* b / a = b conj(a) / |a|²: log|b/a| and arg(b/a) */
      const double re = br * ar + bi * ai, im = bi * ar - br * ai;
      Lg[2 * j] = 0.5 * log((br * br + bi * bi) / (ar * ar + ai * ai));
      Lg[2 * j + 1] = atan2(im, re);
    }
    for (uint32_t j = 0; j < k; ++j) {
      const uint32_t jm = (j + k - 1) % k, jp = (j + 1) % k;
      const double A0r = z[2 * (off + j)] - z[2 * (off + jm)], A0i = z[2 * (off + j) + 1] - z[2 * (off + jm) + 1];
      const double A1r = z[2 * (off + jp)] - z[2 * (off + j)], A1i = z[2 * (off + jp) + 1] - z[2 * (off + j) + 1];
      /* t1 = B_{j+1}/A_{j+1} · L_j,  t0 = B_{j−1}/A_j · L_{j−1} */
      const double n1 = A1r * A1r + A1i * A1i, n0 = A0r * A0r + A0i * A0i;
      const double q1r = (B[2 * jp] * A1r + B[2 * jp + 1] * A1i) / n1, q1i = (B[2 * jp + 1] * A1r - B[2 * jp] * A1i) / n1;
      const double q0r = (B[2 * jm] * A0r + B[2 * jm + 1] * A0i) / n0, q0i = (B[2 * jm + 1] * A0r - B[2 * jm] * A0i) / n0;
      const double t1r = q1r * Lg[2 * j] - q1i * Lg[2 * j + 1], t1i = q1r * Lg[2 * j + 1] + q1i * Lg[2 * j];
      const double t0r = q0r * Lg[2 * jm] - q0i * Lg[2 * jm + 1], t0i = q0r * Lg[2 * jm + 1] + q0i * Lg[2 * jm];
      const double dr = t1r - t0r, di = t1i - t0i;
      /* divide by 2πi: (dr + i di) / (2π i) = (di − i dr) / (2π) */
      C[2 * (off + j)] = di / (2 * HSIB_PI);
      C[2 * (off + j) + 1] = -dr / (2 * HSIB_PI);
      if (D) {
        /* e0 = L_{j−1}/A_j, e1 = L_j/A_{j+1} (L conj(A) / |A|²) */
        const double e0r = (Lg[2 * jm] * A0r + Lg[2 * jm + 1] * A0i) / n0, e0i = (Lg[2 * jm + 1] * A0r - Lg[2 * jm] * A0i) / n0;
        const double e1r = (Lg[2 * j] * A1r + Lg[2 * j + 1] * A1i) / n1, e1i = (Lg[2 * j + 1] * A1r - Lg[2 * j] * A1i) / n1;
        D[2 * (off + j)] = (e0i - e1i) / (2 * HSIB_PI);
        D[2 * (off + j) + 1] = -(e0r - e1r) / (2 * HSIB_PI);
      }
    }
    off += k;
  }
}

static double hsib__segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  const double ex = ax + t * dx - px, ey = ay + t * dy - py;
  return sqrt(ex * ex + ey * ey);
}

/* 0 if w is strictly inside the cage domain (inside loop 0, outside the others, off
 * every cage edge by more than eps); else the loop that excludes it, plus one. */
static uint32_t hsib__outside_cage(const hsib_sequence* s, double wx, double wy, double eps) {
  uint32_t off = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) {
    const uint32_t k = s->loop_sizes[l];
    int inside = 0;
    for (uint32_t j = 0, i = k - 1; j < k; i = j++) {
      const double xj = s->cage[2 * (off + j)], yj = s->cage[2 * (off + j) + 1];
      const double xi = s->cage[2 * (off + i)], yi = s->cage[2 * (off + i) + 1];
      if (((yj > wy) != (yi > wy)) && (wx < (xi - xj) * (wy - yj) / (yi - yj) + xj)) inside = !inside;
      if (hsib__segment_distance(wx, wy, xi, yi, xj, yj) <= eps) return l + 1;
    }
    if ((l == 0) != (inside != 0)) return l + 1;
    off += k;
  }
  return 0;
}

static double hsib__cage_size(const hsib_sequence* s) {
  double x0 = s->cage[0], x1 = x0, y0 = s->cage[1], y1 = y0;
  for (uint32_t j = 0; j < s->info.cage_vertex_count; ++j) {
    const double x = s->cage[2 * j], y = s->cage[2 * j + 1];
    x0 = x < x0 ? x : x0;
    x1 = x > x1 ? x : x1;
    y0 = y < y0 ? y : y0;
    y1 = y > y1 ? y : y1;
  }
  return hypot(x1 - x0, y1 - y0);
}

/* Scratch (doubles) the basis rows at a point take: C and C' (2m each), 4 per vertex of the largest loop. */
static size_t hsib__max_loop(const hsib_sequence* s) {
  size_t k = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) k = s->loop_sizes[l] > k ? s->loop_sizes[l] : k;
  return k;
}
/* C (2m), the loop scratch (4 per vertex of the largest loop), then C' (2m) only for derivatives. */
static size_t hsib__row_scratch(const hsib_sequence* s, int derivatives) {
  return (derivatives ? 4 : 2) * (size_t)s->info.cage_vertex_count + 4 * hsib__max_loop(s);
}

/* The basis row at w (row[r * stride]) and, when dx is not NULL, its derivatives
 * ∂row/∂x, ∂row/∂y (dx[r * stride], dy[r * stride]). The Cauchy coordinates are
 * holomorphic, so with C' = D: ∂x Re C = Re D, ∂y Re C = −Im D, ∂x Im C = Im D,
 * ∂y Im C = Re D; and ∇ log|w − ρ| = (w − ρ)/|w − ρ|². scratch: hsib__row_scratch. */
static void hsib__basis_row(const hsib_sequence* s, double wx, double wy, double* scratch, float* row, float* dx, float* dy, size_t stride) {
  const size_t m = s->info.cage_vertex_count;
  double* C = scratch;
  double* D = dx ? scratch + 2 * m + 4 * hsib__max_loop(s) : NULL;
  hsib__cauchy_coordinates(s, wx, wy, C, D, scratch + 2 * m);
  for (uint32_t r = 0; r < s->info.row_length; ++r) {
    const uint32_t src = s->rows[r], part = src & 3u, col = src >> 2;
    double v, vx = 0, vy = 0;
    if (part < 2u) {
      v = C[2 * col + part];
      if (D) {
        const double Dr = D[2 * col], Di = D[2 * col + 1];
        vx = part == 0u ? Dr : Di;
        vy = part == 0u ? -Di : Dr;
      }
    } else {
      const double ex = wx - s->holes[2 * col], ey = wy - s->holes[2 * col + 1], r2 = ex * ex + ey * ey;
      v = 0.5 * log(r2);
      vx = ex / r2;
      vy = ey / r2;
    }
    row[(size_t)r * stride] = (float)v;
    if (dx) {
      dx[(size_t)r * stride] = (float)vx;
      dy[(size_t)r * stride] = (float)vy;
    }
  }
}

hsib_status hsib_basis_row(const hsib_sequence* s, double x, double y, float* row) {
  if (!s || !row) return HSIB_ERROR_ARGUMENT;
  if (hsib__outside_cage(s, x, y, 1e-9 * hsib__cage_size(s))) return HSIB_ERROR_DOMAIN;
  double* scratch = (double*)hsib_alloc(sizeof(double) * hsib__row_scratch(s, 0));
  if (!scratch) return HSIB_ERROR_MEMORY;
  hsib__basis_row(s, x, y, scratch, row, NULL, NULL, 1);
  hsib_free(scratch);
  return HSIB_OK;
}

hsib_status hsib_basis_row_derivatives(const hsib_sequence* s, double x, double y, float* row, float* dx, float* dy) {
  if (!s || !row || !dx || !dy) return HSIB_ERROR_ARGUMENT;
  if (hsib__outside_cage(s, x, y, 1e-9 * hsib__cage_size(s))) return HSIB_ERROR_DOMAIN;
  double* scratch = (double*)hsib_alloc(sizeof(double) * hsib__row_scratch(s, 1));
  if (!scratch) return HSIB_ERROR_MEMORY;
  hsib__basis_row(s, x, y, scratch, row, dx, dy, 1);
  hsib_free(scratch);
  return HSIB_OK;
}

/* ---------------------------------------------------------------- regions */

/* Even-odd over every shape loop (the outer one and the holes). */
static int hsib__inside_shape(const hsib_sequence* s, double wx, double wy) {
  int inside = 0;
  uint32_t off = 0;
  for (uint32_t l = 0; l < s->info.shape_loop_count; ++l) {
    const uint32_t k = s->shape_sizes[l];
    for (uint32_t j = 0, i = k - 1; j < k; i = j++) {
      const double xj = s->shape[2 * (off + j)], yj = s->shape[2 * (off + j) + 1];
      const double xi = s->shape[2 * (off + i)], yi = s->shape[2 * (off + i) + 1];
      if (((yj > wy) != (yi > wy)) && (wx < (xi - xj) * (wy - yj) / (yi - yj) + xj)) inside = !inside;
    }
    off += k;
  }
  return inside;
}

hsib_region hsib_point_region(const hsib_sequence* s, double x, double y) {
  if (!s || !isfinite(x) || !isfinite(y) || hsib__outside_cage(s, x, y, 1e-9 * hsib__cage_size(s))) return HSIB_REGION_OUTSIDE;
  return s->info.shape_loop_count > 0 && hsib__inside_shape(s, x, y) ? HSIB_REGION_SHAPE : HSIB_REGION_CAGE;
}

/* The point of the cage domain nearest (x, y), a small step inside it: the nearest
 * point on a cage edge, moved off the edge along its normal (to whichever side is
 * inside). 0 when no step up to 1e-3 of the cage's size lands inside (a sliver). */
static int hsib__clamp_to_cage(const hsib_sequence* s, double* x, double* y) {
  const double size = hsib__cage_size(s), eps = 1e-9 * size;
  double best = INFINITY, px = 0, py = 0, nx = 0, ny = 0;
  uint32_t off = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) {
    const uint32_t k = s->loop_sizes[l];
    for (uint32_t j = 0, i = k - 1; j < k; i = j++) {
      const double ax = s->cage[2 * (off + i)], ay = s->cage[2 * (off + i) + 1], bx = s->cage[2 * (off + j)], by = s->cage[2 * (off + j) + 1];
      const double d = hsib__segment_distance(*x, *y, ax, ay, bx, by);
      if (d < best) {
        const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
        double t = l2 > 0 ? ((*x - ax) * dx + (*y - ay) * dy) / l2 : 0;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        best = d;
        px = ax + t * dx;
        py = ay + t * dy;
        const double len = sqrt(l2 > 0 ? l2 : 1);
        nx = -dy / len;
        ny = dx / len;
      }
    }
    off += k;
  }
  for (double step = 1e-6 * size; step <= 1e-3 * size; step *= 4) {
    for (int side = -1; side <= 1; side += 2) {
      const double qx = px + side * step * nx, qy = py + side * step * ny;
      if (!hsib__outside_cage(s, qx, qy, eps)) {
        *x = qx;
        *y = qy;
        return 1;
      }
    }
  }
  return 0;
}

/* ---------------------------------------------------------------- bindings */

/* One block: this struct, then the rows (panels x R x HSIB_PANEL floats), then, with
 * HSIB_BIND_DERIVATIVES, the derivative rows (panels x 2R x HSIB_PANEL: per panel
 * the R rows ∂/∂x, then the R rows ∂/∂y). */
struct hsib_binding {
  const hsib_sequence* sequence;
  size_t vertices, panels;
  float* rows;
  float* derivatives; /* NULL without HSIB_BIND_DERIVATIVES */
  uint32_t flags;
  int caller_memory;
};

void hsib_unbind(hsib_binding* b) {
  if (b && !b->caller_memory) hsib_free(b);
}

size_t hsib_binding_vertex_count(const hsib_binding* b) { return b ? b->vertices : 0; }
const hsib_sequence* hsib_binding_sequence(const hsib_binding* b) { return b ? b->sequence : NULL; }
uint32_t hsib_binding_flags(const hsib_binding* b) { return b ? b->flags : 0u; }

size_t hsib_binding_memory_size_flags(const hsib_sequence* s, size_t vertex_count, uint32_t flags) {
  if (!s || (flags & ~(uint32_t)HSIB_BIND_DERIVATIVES)) return 0;
  const size_t panels = (vertex_count + HSIB_PANEL - 1) / HSIB_PANEL;
  /* rows, and twice as many derivative rows */
  const size_t per_panel = (size_t)s->info.row_length * HSIB_PANEL * sizeof(float) * ((flags & HSIB_BIND_DERIVATIVES) ? 3u : 1u);
  if (panels && per_panel > ((size_t)-1 / 2) / panels) return 0;
  return hsib__align16(sizeof(hsib_binding)) + panels * per_panel + 16;
}

size_t hsib_binding_memory_size(const hsib_sequence* s, size_t vertex_count) { return hsib_binding_memory_size_flags(s, vertex_count, 0u); }

size_t hsib_binding_bytes(const hsib_binding* b) { return b ? hsib_binding_memory_size_flags(b->sequence, b->vertices, b->flags) : 0; }

hsib_status hsib_bind(const hsib_sequence* s, const float* rest_xy, size_t count, size_t stride, hsib_binding** out, char* error,
                      size_t es) {
  return hsib_bind_flags(s, rest_xy, count, stride, NULL, 0u, out, error, es);
}

hsib_status hsib_bind_ex(const hsib_sequence* s, const float* rest_xy, size_t count, size_t stride, const hsib_bind_options* options,
                         hsib_binding** out, char* error, size_t es) {
  return hsib_bind_flags(s, rest_xy, count, stride, options, 0u, out, error, es);
}

hsib_status hsib_bind_flags(const hsib_sequence* s, const float* rest_xy, size_t count, size_t stride, const hsib_bind_options* options,
                            uint32_t flags, hsib_binding** out, char* error, size_t es) {
  if (error && es) error[0] = '\0';
  if (!out) return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: out is NULL");
  *out = NULL;
  if (!s || (!rest_xy && count)) return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: sequence or vertices are NULL");
  if (flags & ~(uint32_t)HSIB_BIND_DERIVATIVES)
    return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind_flags: unknown flags 0x%x (known: HSIB_BIND_DERIVATIVES = 1)", flags);
  if (stride == 0) stride = 2 * sizeof(float);
  if (stride < 2 * sizeof(float)) return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: stride %zu is smaller than two floats", stride);
  const hsib_bind_options defaults = {HSIB_OUTSIDE_REFUSE, NULL, NULL, 0};
  const hsib_bind_options* o = options ? options : &defaults;
  if (o->outside != HSIB_OUTSIDE_REFUSE && o->outside != HSIB_OUTSIDE_CLAMP)
    return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: unknown outside policy %d", (int)o->outside);
  const double eps = 1e-9 * hsib__cage_size(s);
  const unsigned char* in = (const unsigned char*)rest_xy;
  /* All-or-nothing only under HSIB_OUTSIDE_REFUSE: a clamped vertex is reported, not fatal. */
  for (size_t v = 0; v < count; ++v) {
    float xy[2];
    memcpy(xy, in + v * stride, sizeof xy);
    if (!isfinite(xy[0]) || !isfinite(xy[1])) return hsib__fail(error, es, HSIB_ERROR_DOMAIN, "rest vertex %zu is not finite", v);
    const uint32_t l = hsib__outside_cage(s, xy[0], xy[1], eps);
    if (l && o->outside == HSIB_OUTSIDE_REFUSE)
      return hsib__fail(error, es, HSIB_ERROR_DOMAIN,
                  "rest vertex %zu at (%g, %g) lies %s%u: the map is defined inside the cage only (the shape and a margin); "
                  "hsib_bind_ex with HSIB_OUTSIDE_CLAMP binds such vertices to the nearest point inside",
                  v, (double)xy[0], (double)xy[1], l == 1 ? "outside (or on) the cage's outer loop, loop " : "inside (or on) the cage loop of hole ",
                  l == 1 ? 0u : l - 1);
  }
  const size_t need = hsib_binding_memory_size_flags(s, count, flags);
  if (!need) return hsib__fail(error, es, HSIB_ERROR_MEMORY, "hsib_bind: %zu vertices are too many", count);
  hsib_binding* b;
  if (o->memory) {
    if (((uintptr_t)o->memory & 15u) != 0) return hsib__fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: the memory is not 16-byte aligned");
    if (o->memory_bytes < need)
      return hsib__fail(error, es, HSIB_ERROR_MEMORY, "hsib_bind: %zu bytes given, the binding needs %zu (hsib_binding_memory_size%s)", o->memory_bytes,
                        need, flags ? "_flags" : "");
    b = (hsib_binding*)o->memory;
  } else {
    b = (hsib_binding*)hsib_alloc(need);
    if (!b) return hsib__fail(error, es, HSIB_ERROR_MEMORY, "out of memory for the basis rows of %zu vertices (%zu bytes)", count, need);
  }
  memset(b, 0, need);
  const uint32_t R = s->info.row_length;
  const int derivatives = (flags & HSIB_BIND_DERIVATIVES) != 0;
  b->caller_memory = o->memory != NULL;
  b->sequence = s;
  b->vertices = count;
  b->panels = (count + HSIB_PANEL - 1) / HSIB_PANEL;
  b->flags = flags;
  b->rows = (float*)(void*)((unsigned char*)b + hsib__align16(sizeof *b));
  b->derivatives = derivatives ? b->rows + b->panels * (size_t)R * HSIB_PANEL : NULL;
  double stack_C[2048]; /* 16 KB: a single-loop cage of up to 341 vertices (170 with derivatives) */
  const size_t scratch = hsib__row_scratch(s, derivatives);
  double* C = scratch <= 2048 ? stack_C : (double*)hsib_alloc(sizeof(double) * scratch);
  if (!C) {
    hsib_unbind(b);
    return hsib__fail(error, es, HSIB_ERROR_MEMORY, "out of memory (%zu bytes of scratch)", sizeof(double) * scratch);
  }
  for (size_t v = 0; v < count; ++v) {
    float xy[2];
    memcpy(xy, in + v * stride, sizeof xy);
    double x = xy[0], y = xy[1];
    uint8_t region;
    if (hsib__outside_cage(s, x, y, eps)) {
      if (!hsib__clamp_to_cage(s, &x, &y)) {
        if (C != stack_C) hsib_free(C);
        hsib_unbind(b);
        return hsib__fail(error, es, HSIB_ERROR_DOMAIN, "rest vertex %zu at (%g, %g): no point of the cage domain near it to clamp to", v, x, y);
      }
      region = HSIB_REGION_OUTSIDE;
    } else {
      region = (uint8_t)(s->info.shape_loop_count > 0 && hsib__inside_shape(s, x, y) ? HSIB_REGION_SHAPE : HSIB_REGION_CAGE);
    }
    if (o->vertex_region) o->vertex_region[v] = region;
    const size_t p = v / HSIB_PANEL, i = v % HSIB_PANEL;
    float* panel = b->rows + p * (size_t)R * HSIB_PANEL;
    float* dpanel = derivatives ? b->derivatives + p * 2 * (size_t)R * HSIB_PANEL : NULL;
    hsib__basis_row(s, x, y, C, panel + i, dpanel ? dpanel + i : NULL, dpanel ? dpanel + (size_t)R * HSIB_PANEL + i : NULL, HSIB_PANEL);
  }
  if (C != stack_C) hsib_free(C);
  *out = b;
  return HSIB_OK;
}

/* A blend's weights as floats (2R) and its translation, on the stack for R <= 256
 * (so evaluation allocates nothing there), else from the hooks. */
typedef struct hsib__frame_values {
  double stack_w[1024];
  float stack_wf[512];
  double* w;
  float* wf;
  double c[2];
} hsib__frame_values;

static void hsib__frame_values_release(hsib__frame_values* fv) {
  if (fv->w && fv->w != fv->stack_w) hsib_free(fv->w);
  if (fv->wf && fv->wf != fv->stack_wf) hsib_free(fv->wf);
}

static hsib_status hsib__frame_values_make(const hsib_sequence* s, const hsib_blend* blend, hsib__frame_values* fv) {
  const uint32_t R = s->info.row_length;
  fv->w = 4 * (size_t)R <= 1024 ? fv->stack_w : (double*)hsib_alloc(sizeof(double) * 4 * R);
  fv->wf = 2 * (size_t)R <= 512 ? fv->stack_wf : (float*)hsib_alloc(sizeof(float) * 2 * R);
  if (!fv->w || !fv->wf) {
    hsib__frame_values_release(fv);
    return HSIB_ERROR_MEMORY;
  }
  hsib__blend_weights(s, blend, fv->w, fv->wf, fv->c);
  return HSIB_OK;
}

static int hsib__range_valid(const hsib_binding* b, const hsib_blend* blend, size_t first, size_t count, const float* out) {
  return b && (out || !count) && hsib__blend_valid(b->sequence, blend) && first <= b->vertices && count <= b->vertices - first;
}

hsib_status hsib_evaluate_blend_range(const hsib_binding* b, const hsib_blend* blend, size_t first, size_t count, float* out_xy,
                                      size_t out_stride) {
  if (!hsib__range_valid(b, blend, first, count, out_xy)) return HSIB_ERROR_ARGUMENT;
  if (out_stride == 0) out_stride = 2 * sizeof(float);
  const hsib_sequence* s = b->sequence;
  const uint32_t R = s->info.row_length;
  hsib__frame_values fv;
  if (hsib__frame_values_make(s, blend, &fv) != HSIB_OK) return HSIB_ERROR_MEMORY;
  const float* wf = fv.wf;
  const float cx = (float)fv.c[0], cy = (float)fv.c[1];
  unsigned char* out = (unsigned char*)out_xy;
  const size_t end = first + count;
  for (size_t p = first / HSIB_PANEL; p * HSIB_PANEL < end; ++p) {
    float ax[HSIB_PANEL], ay[HSIB_PANEL];
    for (int i = 0; i < HSIB_PANEL; ++i) ax[i] = ay[i] = 0.0f;
    const float* panel = b->rows + p * (size_t)R * HSIB_PANEL;
    for (uint32_t r = 0; r < R; ++r) {
      const float wx = wf[2 * r], wy = wf[2 * r + 1];
      const float* row = panel + (size_t)r * HSIB_PANEL;
      for (int i = 0; i < HSIB_PANEL; ++i) {
        ax[i] += row[i] * wx;
        ay[i] += row[i] * wy;
      }
    }
    const size_t v0 = p * HSIB_PANEL > first ? p * HSIB_PANEL : first;
    const size_t v1 = (p + 1) * HSIB_PANEL < end ? (p + 1) * HSIB_PANEL : end;
    for (size_t v = v0; v < v1; ++v) {
      const float xy[2] = {ax[v - p * HSIB_PANEL] + cx, ay[v - p * HSIB_PANEL] + cy};
      memcpy(out + (v - first) * out_stride, xy, sizeof xy);
    }
  }
  hsib__frame_values_release(&fv);
  return HSIB_OK;
}

hsib_status hsib_evaluate_blend(const hsib_binding* b, const hsib_blend* blend, float* out_xy, size_t out_stride) {
  if (!b) return HSIB_ERROR_ARGUMENT;
  return hsib_evaluate_blend_range(b, blend, 0, b->vertices, out_xy, out_stride);
}

hsib_status hsib_evaluate_range(const hsib_binding* b, uint32_t frame, size_t first, size_t count, float* out_xy, size_t out_stride) {
  const hsib_blend one = {frame, frame, 0.0f, 0};
  return hsib_evaluate_blend_range(b, &one, first, count, out_xy, out_stride);
}

hsib_status hsib_evaluate(const hsib_binding* b, uint32_t frame, float* out_xy, size_t out_stride) {
  if (!b) return HSIB_ERROR_ARGUMENT;
  return hsib_evaluate_range(b, frame, 0, b->vertices, out_xy, out_stride);
}

/* ---------------------------------------------------------------- distortion */

void hsib_singular_values(const float jacobian[4], float sigma[2]) {
  /* J = [a b; c d] (columns ∂f/∂x = (a, c), ∂f/∂y = (b, d)): f_z = ½((a + d) + i(c − b)),
   * f_zbar = ½((a − d) + i(c + b)); σ1 = |f_z| + |f_zbar|, σ2 = |f_z| − |f_zbar|. */
  const double a = jacobian[0], c = jacobian[1], b = jacobian[2], d = jacobian[3];
  const double fz = 0.5 * hypot(a + d, c - b), fzbar = 0.5 * hypot(a - d, c + b);
  sigma[0] = (float)(fz + fzbar);
  sigma[1] = (float)(fz - fzbar);
}

/* The blend's Jacobian (jacobian != 0: 4 floats a vertex) or singular values (2 floats)
 * of vertices [first, first + count): the derivative rows times the blended weights,
 * panel by panel as hsib_evaluate_blend_range does the positions. */
static hsib_status hsib__evaluate_derivatives(const hsib_binding* b, const hsib_blend* blend, size_t first, size_t count, float* out_f,
                                              size_t out_stride, int jacobian) {
  if (!hsib__range_valid(b, blend, first, count, out_f) || !b->derivatives) return HSIB_ERROR_ARGUMENT;
  if (out_stride == 0) out_stride = (jacobian ? 4 : 2) * sizeof(float);
  const hsib_sequence* s = b->sequence;
  const uint32_t R = s->info.row_length;
  hsib__frame_values fv;
  if (hsib__frame_values_make(s, blend, &fv) != HSIB_OK) return HSIB_ERROR_MEMORY;
  const float* wf = fv.wf;
  unsigned char* out = (unsigned char*)out_f;
  const size_t end = first + count;
  for (size_t p = first / HSIB_PANEL; p * HSIB_PANEL < end; ++p) {
    /* ∂f/∂x = (a, c), ∂f/∂y = (b, d) */
    float ja[HSIB_PANEL], jb[HSIB_PANEL], jc[HSIB_PANEL], jd[HSIB_PANEL];
    for (int i = 0; i < HSIB_PANEL; ++i) ja[i] = jb[i] = jc[i] = jd[i] = 0.0f;
    const float* panel = b->derivatives + p * 2 * (size_t)R * HSIB_PANEL;
    for (uint32_t r = 0; r < R; ++r) {
      const float wx = wf[2 * r], wy = wf[2 * r + 1];
      const float* dx = panel + (size_t)r * HSIB_PANEL;
      const float* dy = panel + ((size_t)R + r) * HSIB_PANEL;
      for (int i = 0; i < HSIB_PANEL; ++i) {
        ja[i] += dx[i] * wx;
        jc[i] += dx[i] * wy;
        jb[i] += dy[i] * wx;
        jd[i] += dy[i] * wy;
      }
    }
    const size_t v0 = p * HSIB_PANEL > first ? p * HSIB_PANEL : first;
    const size_t v1 = (p + 1) * HSIB_PANEL < end ? (p + 1) * HSIB_PANEL : end;
    for (size_t v = v0; v < v1; ++v) {
      const size_t i = v - p * HSIB_PANEL;
      const float J[4] = {ja[i], jc[i], jb[i], jd[i]};
      if (jacobian) {
        memcpy(out + (v - first) * out_stride, J, sizeof J);
      } else {
        float sigma[2];
        hsib_singular_values(J, sigma);
        memcpy(out + (v - first) * out_stride, sigma, sizeof sigma);
      }
    }
  }
  hsib__frame_values_release(&fv);
  return HSIB_OK;
}

hsib_status hsib_evaluate_jacobian_range(const hsib_binding* b, const hsib_blend* blend, size_t first, size_t count, float* out_jacobian,
                                         size_t out_stride) {
  return hsib__evaluate_derivatives(b, blend, first, count, out_jacobian, out_stride, 1);
}

hsib_status hsib_evaluate_blend_distortion_range(const hsib_binding* b, const hsib_blend* blend, size_t first, size_t count, float* out_sigma,
                                                 size_t out_stride) {
  return hsib__evaluate_derivatives(b, blend, first, count, out_sigma, out_stride, 0);
}

hsib_status hsib_evaluate_blend_distortion(const hsib_binding* b, const hsib_blend* blend, float* out_sigma, size_t out_stride) {
  if (!b) return HSIB_ERROR_ARGUMENT;
  return hsib_evaluate_blend_distortion_range(b, blend, 0, b->vertices, out_sigma, out_stride);
}

hsib_status hsib_evaluate_distortion(const hsib_binding* b, uint32_t frame, float* out_sigma, size_t out_stride) {
  const hsib_blend one = {frame, frame, 0.0f, 0};
  return hsib_evaluate_blend_distortion(b, &one, out_sigma, out_stride);
}

/* ---------------------------------------------------------------- GPU playback */

uint32_t hsib_gpu_texels_per_vertex(const hsib_sequence* s) { return s ? (s->info.row_length + 3u) / 4u : 0u; }

/* Floats of an image `width` texels wide holding texels_per_vertex texels of every vertex. */
static size_t hsib__gpu_floats(const hsib_binding* b, uint32_t width, size_t texels_per_vertex) {
  const size_t texels = b->vertices * texels_per_vertex;
  const size_t lines = (texels + width - 1) / width;
  return 4u * (size_t)width * (lines ? lines : 1u);
}

size_t hsib_gpu_rows_floats(const hsib_binding* b, uint32_t width) {
  if (!b || width == 0) return 0;
  return hsib__gpu_floats(b, width, hsib_gpu_texels_per_vertex(b->sequence));
}

hsib_status hsib_gpu_rows(const hsib_binding* b, uint32_t width, float* texels) {
  if (!b || !texels || width == 0) return HSIB_ERROR_ARGUMENT;
  const uint32_t R = b->sequence->info.row_length, T = hsib_gpu_texels_per_vertex(b->sequence);
  memset(texels, 0, sizeof(float) * hsib_gpu_rows_floats(b, width));
  for (size_t v = 0; v < b->vertices; ++v) {
    const float* panel = b->rows + (v / HSIB_PANEL) * (size_t)R * HSIB_PANEL;
    float* out = texels + 4u * (v * T);  /* texel v*T + q, 4 floats each, line after line */
    for (uint32_t r = 0; r < R; ++r) out[r] = panel[(size_t)r * HSIB_PANEL + v % HSIB_PANEL];
  }
  return HSIB_OK;
}

size_t hsib_gpu_derivative_rows_floats(const hsib_binding* b, uint32_t width) {
  if (!b || !b->derivatives || width == 0) return 0;
  return hsib__gpu_floats(b, width, 2u * (size_t)hsib_gpu_texels_per_vertex(b->sequence));
}

hsib_status hsib_gpu_derivative_rows(const hsib_binding* b, uint32_t width, float* texels) {
  if (!b || !b->derivatives || !texels || width == 0) return HSIB_ERROR_ARGUMENT;
  const uint32_t R = b->sequence->info.row_length, T = hsib_gpu_texels_per_vertex(b->sequence);
  memset(texels, 0, sizeof(float) * hsib_gpu_derivative_rows_floats(b, width));
  for (size_t v = 0; v < b->vertices; ++v) {
    const float* panel = b->derivatives + (v / HSIB_PANEL) * 2 * (size_t)R * HSIB_PANEL + v % HSIB_PANEL;
    float* out = texels + 4u * (v * 2u * T);  /* texel 2(v*T + q): ∂x rows 4q..4q+3; texel 2(v*T + q) + 1: ∂y rows */
    for (uint32_t r = 0; r < R; ++r) {
      const uint32_t q = r / 4u, c = r % 4u;
      out[8u * q + c] = panel[(size_t)r * HSIB_PANEL];
      out[8u * q + 4u + c] = panel[((size_t)R + r) * HSIB_PANEL];
    }
  }
  return HSIB_OK;
}

hsib_status hsib_gpu_uniforms(const hsib_sequence* s, const hsib_blend* b, float* uniforms) {
  if (!hsib__blend_valid(s, b) || !uniforms) return HSIB_ERROR_ARGUMENT;
  const uint32_t R = s->info.row_length;
  double* w = (double*)hsib_alloc(sizeof(double) * 4 * R);
  if (!w) return HSIB_ERROR_MEMORY;
  double c0[2], c1[2];
  hsib__frame_weights(s, b->frame0, w, c0);
  hsib__frame_weights(s, b->frame1, w + 2 * (size_t)R, c1);
  uniforms[0] = (float)c0[0];
  uniforms[1] = (float)c0[1];
  uniforms[2] = (float)c1[0];
  uniforms[3] = (float)c1[1];
  uniforms[4] = b->s;
  uniforms[5] = (float)R;
  uniforms[6] = (float)hsib_gpu_texels_per_vertex(s);
  uniforms[7] = 0.0f;
  for (uint32_t k = 0; k < R; ++k) {
    uniforms[8 + 4 * k] = (float)w[2 * k];
    uniforms[8 + 4 * k + 1] = (float)w[2 * k + 1];
    uniforms[8 + 4 * k + 2] = (float)w[2 * (size_t)R + 2 * k];
    uniforms[8 + 4 * k + 3] = (float)w[2 * (size_t)R + 2 * k + 1];
  }
  hsib_free(w);
  return HSIB_OK;
}
