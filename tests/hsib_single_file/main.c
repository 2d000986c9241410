/* The single-file runtime hsib.h used as a game would: the implementation in this file,
 * declarations only in other.c, nothing linked but libm. Opens a .hsib in caller
 * memory (a static arena, no allocator calls: the hooks count them), binds the stored
 * mesh (version 2) or one vertex (version 1), plays every frame and the blends between
 * them, its distortion (derivative rows), and checks what it gets. Prints "hsib.h ok: ..." on success. */
#define HSIB_IMPLEMENTATION
#include "hsib.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

const char* other_status_name(hsib_status s); /* other.c */

static int allocations = 0;
static void* counting_allocate(size_t bytes, void* user) {
  (void)user;
  ++allocations;
  return malloc(bytes);
}
static void counting_release(void* p, void* user) {
  (void)user;
  free(p);
}

static unsigned char arena_bytes[(1 << 22) + 16];
static unsigned char file_bytes[1 << 22];

#define CHECK(cond)                                                \
  do {                                                             \
    if (!(cond)) {                                                 \
      fprintf(stderr, "hsib.h test: %s failed (line %d)\n", #cond, __LINE__); \
      return 1;                                                    \
    }                                                              \
  } while (0)

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: hsib_single_file FILE.hsib\n");
    return 2;
  }
  FILE* f = fopen(argv[1], "rb");
  CHECK(f != NULL);
  const size_t size = fread(file_bytes, 1, sizeof file_bytes, f);
  fclose(f);
  const hsib_allocator hooks = {counting_allocate, counting_release, NULL};
  hsib_set_allocator(&hooks);
  char error[256];
  size_t need = 0;
  CHECK(hsib_sequence_bytes(file_bytes, size, &need, error, sizeof error) == HSIB_OK);
  hsib_sequence* s = NULL;
  unsigned char* arena = arena_bytes + ((16u - ((uintptr_t)arena_bytes & 15u)) & 15u); /* 16-byte aligned, 4 MiB */
  const size_t arena_size = (size_t)1 << 22;
  CHECK(need <= arena_size / 2);
  if (hsib_open_in_place(file_bytes, size, arena, need, &s, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "hsib.h test: %s\n", error);
    return 1;
  }
  hsib_info info;
  hsib_get_info(s, &info);
  hsib_mesh mesh;
  float one[2] = {(float)(info.bbox[0] + 0.05 * (info.bbox[2] - info.bbox[0])), (float)(0.5 * (info.bbox[1] + info.bbox[3]))};
  const hsib_status ms = hsib_get_mesh(s, &mesh);
  CHECK(ms == (info.version >= 2 ? HSIB_OK : HSIB_ERROR_VERSION));
  const float* rest = ms == HSIB_OK ? mesh.xy : one;
  const size_t count = ms == HSIB_OK ? mesh.vertex_count : 1;
  unsigned char* bind_memory = arena + ((need + 15u) & ~(size_t)15u);
  hsib_bind_options o = {HSIB_OUTSIDE_REFUSE, NULL, bind_memory, arena_size - ((need + 15u) & ~(size_t)15u)};
  hsib_binding* b = NULL;
  if (hsib_bind_ex(s, rest, count, 0, &o, &b, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "hsib.h test: %s\n", error);
    return 1;
  }
  static float out[2 * 200000];
  CHECK(count <= 200000);
  for (uint32_t fr = 0; fr < info.frame_count; ++fr) {
    CHECK(hsib_evaluate(b, fr, out, 0) == HSIB_OK);
    for (size_t k = 0; k < 2 * count; ++k) CHECK(isfinite(out[k]));
  }
  /* Blends half way between frames: between the two frames' images of each vertex
   * exactly (a blend of the weights is the blend of the images). */
  static float a[2 * 200000], c[2 * 200000];
  int blended = 0;
  for (uint32_t fr = 0; fr + 1 < info.frame_count; ++fr) {
    double t0, t1;
    hsib_frame_info(s, fr, &t0, NULL);
    hsib_frame_info(s, fr + 1, &t1, NULL);
    const hsib_blend bl = hsib_blend_at_time(s, 0.5 * (t0 + t1), HSIB_PLAY_BLEND);
    if (!(bl.flags & HSIB_BLEND_BLENDED)) continue;
    ++blended;
    CHECK(hsib_evaluate_blend(b, &bl, out, 0) == HSIB_OK);
    CHECK(hsib_evaluate(b, bl.frame0, a, 0) == HSIB_OK);
    CHECK(hsib_evaluate(b, bl.frame1, c, 0) == HSIB_OK);
    for (size_t k = 0; k < 2 * count; ++k) {
      const double want = (1.0 - bl.s) * a[k] + bl.s * c[k];
      CHECK(fabs(out[k] - want) <= 1e-4 * (1.0 + fabs(want)));
    }
  }
  /* Distortion: the same vertices bound with derivative rows, in the arena after the
   * first binding; sigma1 >= |sigma2| everywhere, and sigma2 > 0 (no fold) for every
   * certified frame at the mesh's vertices (in the shape or on its outline). */
  {
    const size_t first = (hsib_binding_bytes(b) + 15u) & ~(size_t)15u;
    const size_t used = ((need + 15u) & ~(size_t)15u) + first;
    hsib_bind_options od = {HSIB_OUTSIDE_REFUSE, NULL, bind_memory + first, arena_size - used};
    hsib_binding* bd = NULL;
    CHECK(hsib_binding_memory_size_flags(s, count, HSIB_BIND_DERIVATIVES) <= arena_size - used);
    if (hsib_bind_flags(s, rest, count, 0, &od, HSIB_BIND_DERIVATIVES, &bd, error, sizeof error) != HSIB_OK) {
      fprintf(stderr, "hsib.h test: %s\n", error);
      return 1;
    }
    CHECK(hsib_evaluate_distortion(b, 0, out, 0) == HSIB_ERROR_ARGUMENT); /* no derivative rows */
    for (uint32_t fr = 0; fr < info.frame_count; ++fr) {
      uint32_t flags = 0;
      CHECK(hsib_frame_info(s, fr, NULL, &flags) == HSIB_OK);
      uint32_t stop = HSIB_STOP_COUNT;
      CHECK(hsib_frame_stop(s, fr, &stop) == HSIB_OK);
      CHECK((stop == HSIB_STOP_CONVERGED) == ((flags & HSIB_FRAME_CONVERGED) != 0u));
      CHECK(hsib_stop_name(stop)[0] != '\0');
      CHECK(hsib_evaluate_distortion(bd, fr, out, 0) == HSIB_OK);
      for (size_t k = 0; k < count; ++k) {
        CHECK(isfinite(out[2 * k]) && isfinite(out[2 * k + 1]));
        CHECK(out[2 * k] >= fabsf(out[2 * k + 1]));
        if ((flags & HSIB_FRAME_CERTIFIED) && ms == HSIB_OK) CHECK(out[2 * k + 1] > 0.0f);
      }
    }
    hsib_unbind(bd);
  }
  if (ms == HSIB_OK) { /* triangle centroids of the stored mesh lie in the shape */
    uint32_t in_shape = 0;
    for (uint32_t t = 0; t < mesh.triangle_count; ++t) {
      double x = 0, y = 0;
      for (int k = 0; k < 3; ++k) {
        x += mesh.xy[2 * mesh.triangles[3 * t + k]] / 3.0;
        y += mesh.xy[2 * mesh.triangles[3 * t + k] + 1] / 3.0;
      }
      in_shape += hsib_point_region(s, x, y) == HSIB_REGION_SHAPE;
    }
    CHECK(in_shape == mesh.triangle_count);
  }
  hsib_unbind(b);
  hsib_close(s);
  CHECK(allocations == 0);
  printf("hsib.h ok: version %u, %u frames, %zu vertices, %d blended intervals, %s\n", info.version, info.frame_count, count, blended,
         other_status_name(HSIB_OK));
  return 0;
}
