/* The baked playback runtime (format and API in hsi/baked_runtime.h): C99, the C
 * library only. Reads are byte-by-byte little-endian, so it runs on any host. */
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

static void* default_allocate(size_t bytes, void* user) {
  (void)user;
  return malloc(bytes);
}
static void default_release(void* p, void* user) {
  (void)user;
  free(p);
}
static hsib_allocator g_alloc = {default_allocate, default_release, NULL};

void hsib_set_allocator(const hsib_allocator* allocator) {
  if (allocator && allocator->allocate && allocator->release)
    g_alloc = *allocator;
  else {
    g_alloc.allocate = default_allocate;
    g_alloc.release = default_release;
    g_alloc.user = NULL;
  }
}

static void* hsib_alloc(size_t bytes) { return g_alloc.allocate(bytes ? bytes : 1, g_alloc.user); }
static void hsib_free(void* p) {
  if (p) g_alloc.release(p, g_alloc.user);
}
static void* hsib_calloc(size_t count, size_t size) {
  if (size && count > (size_t)-1 / size) return NULL;
  void* p = hsib_alloc(count * size);
  if (p) memset(p, 0, count * size);
  return p;
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

static hsib_status fail(char* error, size_t error_size, hsib_status s, const char* fmt, ...) {
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

static uint32_t rd_u32(const unsigned char* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t rd_u64(const unsigned char* p) { return (uint64_t)rd_u32(p) | ((uint64_t)rd_u32(p + 4) << 32); }
static double rd_f64(const unsigned char* p) {
  const uint64_t u = rd_u64(p);
  double d;
  memcpy(&d, &u, 8);
  return d;
}
static float rd_f32(const unsigned char* p) {
  const uint32_t u = rd_u32(p);
  float f;
  memcpy(&f, &u, 4);
  return f;
}

/* ---------------------------------------------------------------- the sequence */

typedef struct hsib_entry {
  uint32_t target, source;
  double value;
} hsib_entry;

struct hsib_sequence {
  hsib_info info;
  uint32_t* loop_sizes;  /* L */
  double* cage;          /* m x 2 */
  double* holes;         /* N x 2 */
  uint32_t* rows;        /* R row sources */
  hsib_entry* expansion; /* Z */
  uint32_t Z, frame_bytes;
  unsigned char* frames; /* F x frame_bytes, as in the file */
};

static void free_sequence(hsib_sequence* s) {
  if (!s) return;
  hsib_free(s->loop_sizes);
  hsib_free(s->cage);
  hsib_free(s->holes);
  hsib_free(s->rows);
  hsib_free(s->expansion);
  hsib_free(s->frames);
  hsib_free(s);
}

void hsib_close(hsib_sequence* s) { free_sequence(s); }

#define LIMIT_LOOPS 100000u
#define LIMIT_VERTICES 10000000u

static hsib_status parse(const unsigned char* b, size_t size, hsib_sequence* s, char* error, size_t es) {
  if (size < 4) return fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %d", size, HSIB_HEADER_SIZE);
  if (memcmp(b, "HSIB", 4) != 0) return fail(error, es, HSIB_ERROR_FORMAT, "not an hsi baked sequence (magic is not \"HSIB\")");
  if (size < 8) return fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %d", size, HSIB_HEADER_SIZE);
  const uint32_t version = rd_u32(b + 4);
  if (version != HSIB_FORMAT_VERSION)
    return fail(error, es, HSIB_ERROR_VERSION, "unsupported baked format version %u (this runtime reads version %d)", version,
                HSIB_FORMAT_VERSION);
  if (size < HSIB_HEADER_SIZE)
    return fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: %zu bytes, the header alone is %d", size, HSIB_HEADER_SIZE);
  if (rd_u32(b + 92) != hsib_crc32(b, 92))
    return fail(error, es, HSIB_ERROR_CHECKSUM, "header checksum mismatch (bytes 0..91): the file is corrupt");
  if (rd_u32(b + 8) != HSIB_HEADER_SIZE)
    return fail(error, es, HSIB_ERROR_FORMAT, "header size %u, version 1 has %d", rd_u32(b + 8), HSIB_HEADER_SIZE);
  const uint32_t flags = rd_u32(b + 12);
  if (flags > 1u) return fail(error, es, HSIB_ERROR_FORMAT, "unknown header flags 0x%x (at byte 12)", flags);
  const uint32_t L = rd_u32(b + 16), m = rd_u32(b + 20), N = rd_u32(b + 24), R = rd_u32(b + 28), D = rd_u32(b + 32);
  const uint32_t Z = rd_u32(b + 36), F = rd_u32(b + 40), S = rd_u32(b + 44);
  const uint64_t static_bytes = rd_u64(b + 80);
  if (L < 1 || L > LIMIT_LOOPS) return fail(error, es, HSIB_ERROR_FORMAT, "impossible cage loop count %u (at byte 16)", L);
  if (m < 3 * L || m > LIMIT_VERTICES) return fail(error, es, HSIB_ERROR_FORMAT, "impossible cage vertex count %u for %u loops (at byte 20)", m, L);
  if (N != L - 1) return fail(error, es, HSIB_ERROR_FORMAT, "hole count %u does not match %u hole loops (at byte 24)", N, L - 1);
  if (R < 1 || R > 2 * m + N) return fail(error, es, HSIB_ERROR_FORMAT, "impossible basis row length %u (at byte 28)", R);
  if (D < 1 || D > 4 * (m + N)) return fail(error, es, HSIB_ERROR_FORMAT, "impossible coefficient count %u (at byte 32)", D);
  if (Z > 8u * D) return fail(error, es, HSIB_ERROR_FORMAT, "impossible expansion size %u (at byte 36)", Z);
  const uint32_t scalar = (flags & 1u) ? 4u : 8u;
  const uint64_t want_S = 48u + (uint64_t)D * scalar + 4u;
  if (S != want_S) return fail(error, es, HSIB_ERROR_FORMAT, "frame record size %u, the header's sizes give %llu (at byte 44)", S, (unsigned long long)want_S);
  const uint64_t want_static = 4ull * L + 16ull * m + 16ull * N + 4ull * R + 16ull * Z;
  if (static_bytes != want_static)
    return fail(error, es, HSIB_ERROR_FORMAT, "static section size %llu, the header's sizes give %llu (at byte 80)",
                (unsigned long long)static_bytes, (unsigned long long)want_static);
  const uint64_t total = HSIB_HEADER_SIZE + want_static + (uint64_t)F * S;
  if ((uint64_t)size < total)
    return fail(error, es, HSIB_ERROR_TRUNCATED, "truncated: the file has %zu bytes, its header announces %llu (%u frames)", size,
                (unsigned long long)total, F);
  if ((uint64_t)size > total)
    return fail(error, es, HSIB_ERROR_TRUNCATED, "%llu trailing bytes after the last of %u frames", (unsigned long long)(size - total), F);
  const unsigned char* st = b + HSIB_HEADER_SIZE;
  if (rd_u32(b + 88) != hsib_crc32(st, (size_t)want_static))
    return fail(error, es, HSIB_ERROR_CHECKSUM, "static section checksum mismatch (bytes %d..%llu): the file is corrupt", HSIB_HEADER_SIZE,
                (unsigned long long)(HSIB_HEADER_SIZE + want_static - 1));

  hsib_info* in = &s->info;
  in->version = version;
  in->frame_count = F;
  in->loop_count = L;
  in->cage_vertex_count = m;
  in->hole_count = N;
  in->row_length = R;
  in->coefficient_count = D;
  in->single_precision = (int)(flags & 1u);
  for (int k = 0; k < 4; ++k) in->bbox[k] = rd_f64(b + 48 + 8 * k);
  in->file_bytes = size;
  s->Z = Z;
  s->frame_bytes = S;
  s->loop_sizes = (uint32_t*)hsib_calloc(L, 4);
  s->cage = (double*)hsib_calloc(2 * (size_t)m, 8);
  s->holes = (double*)hsib_calloc(2 * (size_t)N + 1, 8);
  s->rows = (uint32_t*)hsib_calloc(R, 4);
  s->expansion = (hsib_entry*)hsib_calloc(Z + 1, sizeof(hsib_entry));
  s->frames = (unsigned char*)hsib_alloc((size_t)F * S);
  if (!s->loop_sizes || !s->cage || !s->holes || !s->rows || !s->expansion || !s->frames)
    return fail(error, es, HSIB_ERROR_MEMORY, "out of memory reading a sequence of %u frames", F);

  const unsigned char* p = st;
  uint64_t msum = 0;
  for (uint32_t l = 0; l < L; ++l, p += 4) {
    s->loop_sizes[l] = rd_u32(p);
    if (s->loop_sizes[l] < 3)
      return fail(error, es, HSIB_ERROR_FORMAT, "cage loop %u has %u vertices (at byte %ld)", l, s->loop_sizes[l], (long)(p - b));
    msum += s->loop_sizes[l];
  }
  if (msum != m) return fail(error, es, HSIB_ERROR_FORMAT, "cage loop sizes sum to %llu, the header says %u", (unsigned long long)msum, m);
  for (uint32_t j = 0; j < 2 * m; ++j, p += 8) {
    s->cage[j] = rd_f64(p);
    if (!isfinite(s->cage[j])) return fail(error, es, HSIB_ERROR_FORMAT, "non-finite cage vertex %u (at byte %ld)", j / 2, (long)(p - b));
  }
  for (uint32_t j = 0; j < 2 * N; ++j, p += 8) {
    s->holes[j] = rd_f64(p);
    if (!isfinite(s->holes[j])) return fail(error, es, HSIB_ERROR_FORMAT, "non-finite hole point %u (at byte %ld)", j / 2, (long)(p - b));
  }
  for (uint32_t r = 0; r < R; ++r, p += 4) {
    const uint32_t src = rd_u32(p), part = src & 3u, col = src >> 2;
    if (part == 3u || (part < 2u && col >= m) || (part == 2u && col >= N))
      return fail(error, es, HSIB_ERROR_FORMAT, "row source %u names column %u part %u, which does not exist (at byte %ld)", r, col, part,
                  (long)(p - b));
    s->rows[r] = src;
  }
  for (uint32_t z = 0; z < Z; ++z, p += 16) {
    hsib_entry* e = &s->expansion[z];
    e->target = rd_u32(p);
    e->source = rd_u32(p + 4);
    e->value = rd_f64(p + 8);
    if (e->target >= 2 * R || e->source >= D || !isfinite(e->value))
      return fail(error, es, HSIB_ERROR_FORMAT, "expansion entry %u (%u, %u) is out of range (at byte %ld)", z, e->target, e->source,
                  (long)(p - b));
  }
  memcpy(s->frames, p, (size_t)F * S);
  for (uint32_t f = 0; f < F; ++f) {
    const unsigned char* fr = s->frames + (size_t)f * S;
    const long at = (long)(p - b) + (long)((size_t)f * S);
    if (rd_u32(fr + S - 4) != hsib_crc32(fr, S - 4))
      return fail(error, es, HSIB_ERROR_CHECKSUM, "frame %u checksum mismatch (record at byte %ld): the file is corrupt", f, at);
    const double t = rd_f64(fr);
    const uint32_t ff = rd_u32(fr + 8);
    if (!isfinite(t) || (f > 0 && !(t >= rd_f64(fr - S))))
      return fail(error, es, HSIB_ERROR_FORMAT, "frame %u: time is not finite or decreases (at byte %ld)", f, at);
    if (ff > 15u) return fail(error, es, HSIB_ERROR_FORMAT, "frame %u: unknown flags 0x%x (at byte %ld)", f, ff, at + 8);
    const double rr = rd_f64(fr + 16), ri = rd_f64(fr + 24);
    if (!isfinite(rr) || !isfinite(ri) || fabs(hypot(rr, ri) - 1.0) > 1e-6 || !isfinite(rd_f64(fr + 32)) || !isfinite(rd_f64(fr + 40)))
      return fail(error, es, HSIB_ERROR_FORMAT, "frame %u: the pose is not a rotation and a finite translation (at byte %ld)", f, at + 16);
    for (uint32_t d = 0; d < D; ++d) {
      const unsigned char* q = fr + 48 + (size_t)d * scalar;
      const double x = scalar == 4 ? (double)rd_f32(q) : rd_f64(q);
      if (!isfinite(x)) return fail(error, es, HSIB_ERROR_FORMAT, "frame %u: coefficient %u is not finite (at byte %ld)", f, d, at + 48 + (long)(d * scalar));
    }
  }
  in->t_begin = F ? rd_f64(s->frames) : 0.0;
  in->t_end = F ? rd_f64(s->frames + (size_t)(F - 1) * S) : 0.0;
  return HSIB_OK;
}

hsib_status hsib_open_memory(const void* data, size_t size, hsib_sequence** out, char* error, size_t error_size) {
  if (error && error_size) error[0] = '\0';
  if (!out) return fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_memory: out is NULL");
  *out = NULL;
  if (!data && size) return fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_memory: data is NULL");
  hsib_sequence* s = (hsib_sequence*)hsib_calloc(1, sizeof(hsib_sequence));
  if (!s) return fail(error, error_size, HSIB_ERROR_MEMORY, "out of memory");
  const hsib_status st = parse((const unsigned char*)data, size, s, error, error_size);
  if (st != HSIB_OK) {
    free_sequence(s);
    return st;
  }
  *out = s;
  return HSIB_OK;
}

hsib_status hsib_open_file(const char* path, hsib_sequence** out, char* error, size_t error_size) {
  if (error && error_size) error[0] = '\0';
  if (!out || !path) return fail(error, error_size, HSIB_ERROR_ARGUMENT, "hsib_open_file: path or out is NULL");
  *out = NULL;
  FILE* f = fopen(path, "rb");
  if (!f) return fail(error, error_size, HSIB_ERROR_IO, "%s: cannot open the baked sequence", path);
  unsigned char* buf = NULL;
  size_t size = 0, cap = 0;
  for (;;) {
    if (size == cap) {
      cap = cap ? 2 * cap : 65536;
      unsigned char* nb = (unsigned char*)hsib_alloc(cap);
      if (!nb) {
        hsib_free(buf);
        fclose(f);
        return fail(error, error_size, HSIB_ERROR_MEMORY, "%s: out of memory reading the file", path);
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
    return fail(error, error_size, HSIB_ERROR_IO, "%s: read error", path);
  }
  char inner[256] = {0};
  const hsib_status st = hsib_open_memory(buf, size, out, inner, sizeof inner);
  hsib_free(buf);
  if (st != HSIB_OK) return fail(error, error_size, st, "%s: %s", path, inner);
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

static const unsigned char* frame_record(const hsib_sequence* s, uint32_t f) { return s->frames + (size_t)f * s->frame_bytes; }

hsib_status hsib_frame_info(const hsib_sequence* s, uint32_t frame, double* t, uint32_t* flags) {
  if (!s || frame >= s->info.frame_count) return HSIB_ERROR_ARGUMENT;
  const unsigned char* fr = frame_record(s, frame);
  if (t) *t = rd_f64(fr);
  if (flags) *flags = rd_u32(fr + 8);
  return HSIB_OK;
}

uint32_t hsib_frame_at_time(const hsib_sequence* s, double t) {
  if (!s || s->info.frame_count == 0) return 0;
  uint32_t lo = 0, hi = s->info.frame_count - 1;
  while (lo < hi) {  /* first frame with time >= t */
    const uint32_t mid = lo + (hi - lo) / 2;
    if (rd_f64(frame_record(s, mid)) < t) lo = mid + 1; else hi = mid;
  }
  if (lo > 0 && fabs(rd_f64(frame_record(s, lo - 1)) - t) <= fabs(rd_f64(frame_record(s, lo)) - t)) --lo;
  return lo;
}

/* w = r · (E x) as doubles (2R), plus the translation. */
static void frame_weights(const hsib_sequence* s, uint32_t frame, double* w, double c[2]) {
  const unsigned char* fr = frame_record(s, frame);
  const uint32_t R = s->info.row_length;
  const int single = s->info.single_precision;
  memset(w, 0, sizeof(double) * 2 * R);
  for (uint32_t z = 0; z < s->Z; ++z) {
    const hsib_entry* e = &s->expansion[z];
    const unsigned char* q = fr + 48 + (size_t)e->source * (single ? 4u : 8u);
    w[e->target] += e->value * (single ? (double)rd_f32(q) : rd_f64(q));
  }
  const double rr = rd_f64(fr + 16), ri = rd_f64(fr + 24);
  for (uint32_t k = 0; k < R; ++k) {
    const double a = w[2 * k], b = w[2 * k + 1];
    w[2 * k] = rr * a - ri * b;
    w[2 * k + 1] = rr * b + ri * a;
  }
  c[0] = rd_f64(fr + 32);
  c[1] = rd_f64(fr + 40);
}

hsib_status hsib_frame_weights(const hsib_sequence* s, uint32_t frame, float* weights, float translation[2]) {
  if (!s || !weights || frame >= s->info.frame_count) return HSIB_ERROR_ARGUMENT;
  const uint32_t R = s->info.row_length;
  double* w = (double*)hsib_alloc(sizeof(double) * 2 * R);
  if (!w) return HSIB_ERROR_MEMORY;
  double c[2];
  frame_weights(s, frame, w, c);
  for (uint32_t k = 0; k < 2 * R; ++k) weights[k] = (float)w[k];
  if (translation) {
    translation[0] = (float)c[0];
    translation[1] = (float)c[1];
  }
  hsib_free(w);
  return HSIB_OK;
}

/* ---------------------------------------------------------------- basis rows */

/* Cauchy coordinates of every cage vertex at w (math.md §2; engine/src/basis.cpp is
 * the reference): C_j = 1/(2πi) [B_{j+1}/A_{j+1} log(B_{j+1}/B_j) − B_{j−1}/A_j log(B_j/B_{j−1})],
 * written out in real arithmetic. C has 2m doubles (re, im). */
static void cauchy_coordinates(const hsib_sequence* s, double wx, double wy, double* C, double* scratch) {
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
    }
    off += k;
  }
}

static double segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  const double ex = ax + t * dx - px, ey = ay + t * dy - py;
  return sqrt(ex * ex + ey * ey);
}

/* 0 if w is strictly inside the cage domain (inside loop 0, outside the others, off
 * every cage edge by more than eps); else the loop that excludes it, plus one. */
static uint32_t outside_cage(const hsib_sequence* s, double wx, double wy, double eps) {
  uint32_t off = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) {
    const uint32_t k = s->loop_sizes[l];
    int inside = 0;
    for (uint32_t j = 0, i = k - 1; j < k; i = j++) {
      const double xj = s->cage[2 * (off + j)], yj = s->cage[2 * (off + j) + 1];
      const double xi = s->cage[2 * (off + i)], yi = s->cage[2 * (off + i) + 1];
      if (((yj > wy) != (yi > wy)) && (wx < (xi - xj) * (wy - yj) / (yi - yj) + xj)) inside = !inside;
      if (segment_distance(wx, wy, xi, yi, xj, yj) <= eps) return l + 1;
    }
    if ((l == 0) != (inside != 0)) return l + 1;
    off += k;
  }
  return 0;
}

static double cage_size(const hsib_sequence* s) {
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

static void basis_row(const hsib_sequence* s, double wx, double wy, double* C, double* scratch, float* row, size_t row_stride) {
  cauchy_coordinates(s, wx, wy, C, scratch);
  for (uint32_t r = 0; r < s->info.row_length; ++r) {
    const uint32_t src = s->rows[r], part = src & 3u, col = src >> 2;
    double v;
    if (part < 2u)
      v = C[2 * col + part];
    else
      v = 0.5 * log((wx - s->holes[2 * col]) * (wx - s->holes[2 * col]) + (wy - s->holes[2 * col + 1]) * (wy - s->holes[2 * col + 1]));
    row[(size_t)r * row_stride] = (float)v;
  }
}

static size_t max_loop(const hsib_sequence* s) {
  size_t k = 0;
  for (uint32_t l = 0; l < s->info.loop_count; ++l) k = s->loop_sizes[l] > k ? s->loop_sizes[l] : k;
  return k;
}

hsib_status hsib_basis_row(const hsib_sequence* s, double x, double y, float* row) {
  if (!s || !row) return HSIB_ERROR_ARGUMENT;
  if (outside_cage(s, x, y, 1e-9 * cage_size(s))) return HSIB_ERROR_DOMAIN;
  double* C = (double*)hsib_alloc(sizeof(double) * (2 * (size_t)s->info.cage_vertex_count + 4 * max_loop(s)));
  if (!C) return HSIB_ERROR_MEMORY;
  basis_row(s, x, y, C, C + 2 * (size_t)s->info.cage_vertex_count, row, 1);
  hsib_free(C);
  return HSIB_OK;
}

/* ---------------------------------------------------------------- bindings */

struct hsib_binding {
  const hsib_sequence* sequence;
  size_t vertices, panels;
  float* rows; /* panels x R x HSIB_PANEL */
};

void hsib_unbind(hsib_binding* b) {
  if (!b) return;
  hsib_free(b->rows);
  hsib_free(b);
}

size_t hsib_binding_vertex_count(const hsib_binding* b) { return b ? b->vertices : 0; }
size_t hsib_binding_bytes(const hsib_binding* b) {
  return b ? sizeof *b + b->panels * (size_t)b->sequence->info.row_length * HSIB_PANEL * sizeof(float) : 0;
}

hsib_status hsib_bind(const hsib_sequence* s, const float* rest_xy, size_t count, size_t stride, hsib_binding** out, char* error,
                      size_t es) {
  if (error && es) error[0] = '\0';
  if (!out) return fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: out is NULL");
  *out = NULL;
  if (!s || (!rest_xy && count)) return fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: sequence or vertices are NULL");
  if (stride == 0) stride = 2 * sizeof(float);
  if (stride < 2 * sizeof(float)) return fail(error, es, HSIB_ERROR_ARGUMENT, "hsib_bind: stride %zu is smaller than two floats", stride);
  const double eps = 1e-9 * cage_size(s);
  const unsigned char* in = (const unsigned char*)rest_xy;
  for (size_t v = 0; v < count; ++v) {
    float xy[2];
    memcpy(xy, in + v * stride, sizeof xy);
    if (!isfinite(xy[0]) || !isfinite(xy[1]))
      return fail(error, es, HSIB_ERROR_DOMAIN, "rest vertex %zu is not finite", v);
    const uint32_t l = outside_cage(s, xy[0], xy[1], eps);
    if (l)
      return fail(error, es, HSIB_ERROR_DOMAIN,
                  "rest vertex %zu at (%g, %g) lies %s%u: the map is defined inside the cage only (the shape and a margin)", v,
                  (double)xy[0], (double)xy[1], l == 1 ? "outside (or on) the cage's outer loop, loop " : "inside (or on) the cage loop of hole ",
                  l == 1 ? 0u : l - 1);
  }
  hsib_binding* b = (hsib_binding*)hsib_calloc(1, sizeof(hsib_binding));
  if (!b) return fail(error, es, HSIB_ERROR_MEMORY, "out of memory");
  const uint32_t R = s->info.row_length;
  b->sequence = s;
  b->vertices = count;
  b->panels = (count + HSIB_PANEL - 1) / HSIB_PANEL;
  b->rows = (float*)hsib_calloc(b->panels * (size_t)R * HSIB_PANEL + 1, sizeof(float));
  double* C = (double*)hsib_alloc(sizeof(double) * (2 * (size_t)s->info.cage_vertex_count + 4 * max_loop(s)));
  if (!b->rows || !C) {
    hsib_free(C);
    hsib_unbind(b);
    return fail(error, es, HSIB_ERROR_MEMORY, "out of memory for the basis rows of %zu vertices (%zu bytes)", count,
                b->panels * (size_t)R * HSIB_PANEL * sizeof(float));
  }
  for (size_t v = 0; v < count; ++v) {
    float xy[2];
    memcpy(xy, in + v * stride, sizeof xy);
    float* panel = b->rows + (v / HSIB_PANEL) * (size_t)R * HSIB_PANEL;
    basis_row(s, xy[0], xy[1], C, C + 2 * (size_t)s->info.cage_vertex_count, panel + v % HSIB_PANEL, HSIB_PANEL);
  }
  hsib_free(C);
  *out = b;
  return HSIB_OK;
}

hsib_status hsib_evaluate_range(const hsib_binding* b, uint32_t frame, size_t first, size_t count, float* out_xy, size_t out_stride) {
  if (!b || (!out_xy && count) || frame >= b->sequence->info.frame_count || first > b->vertices || count > b->vertices - first)
    return HSIB_ERROR_ARGUMENT;
  if (out_stride == 0) out_stride = 2 * sizeof(float);
  const hsib_sequence* s = b->sequence;
  const uint32_t R = s->info.row_length;
  double stack_w[1024];
  double* w = 2 * (size_t)R <= 1024 ? stack_w : (double*)hsib_alloc(sizeof(double) * 2 * R);
  float stack_wf[1024];
  float* wf = 2 * (size_t)R <= 1024 ? stack_wf : (float*)hsib_alloc(sizeof(float) * 2 * R);
  if (!w || !wf) {
    if (w != stack_w) hsib_free(w);
    if (wf != stack_wf) hsib_free(wf);
    return HSIB_ERROR_MEMORY;
  }
  double c[2];
  frame_weights(s, frame, w, c);
  for (uint32_t k = 0; k < 2 * R; ++k) wf[k] = (float)w[k];
  const float cx = (float)c[0], cy = (float)c[1];
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
  if (w != stack_w) hsib_free(w);
  if (wf != stack_wf) hsib_free(wf);
  return HSIB_OK;
}

hsib_status hsib_evaluate(const hsib_binding* b, uint32_t frame, float* out_xy, size_t out_stride) {
  if (!b) return HSIB_ERROR_ARGUMENT;
  return hsib_evaluate_range(b, frame, 0, b->vertices, out_xy, out_stride);
}
