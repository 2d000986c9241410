/* The baked runtime's glue for JavaScript (web/player.js): plain values and pointers
 * instead of the structs that hsi/baked_runtime.h passes by value. Compiled to
 * WebAssembly with the runtime itself (web/CMakeLists.txt). */
#include <stdio.h>

#include "hsi/baked_runtime.h"

hsib_sequence* hsib_web_open(const void* data, size_t size);
uint32_t hsib_web_frame_count(const hsib_sequence* s);
double hsib_web_frame_time(const hsib_sequence* s, uint32_t frame);
uint32_t hsib_web_row_length(const hsib_sequence* s);
uint32_t hsib_web_mesh_vertex_count(const hsib_sequence* s);
uint32_t hsib_web_mesh_triangle_count(const hsib_sequence* s);
const float* hsib_web_mesh_xy(const hsib_sequence* s);
const float* hsib_web_mesh_uv(const hsib_sequence* s);
const uint32_t* hsib_web_mesh_triangles(const hsib_sequence* s);
hsib_binding* hsib_web_bind(const hsib_sequence* s, const float* xy, uint32_t count, uint32_t flags);
void hsib_web_blend_at_time(const hsib_sequence* s, double t, int mode, hsib_blend* out);

/* NULL on failure, with the runtime's message on the console. */
hsib_sequence* hsib_web_open(const void* data, size_t size) {
  hsib_sequence* s = NULL;
  char error[256];
  if (hsib_open_memory(data, size, &s, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "hsib: %s\n", error);
    return NULL;
  }
  return s;
}

uint32_t hsib_web_frame_count(const hsib_sequence* s) {
  hsib_info info;
  hsib_get_info(s, &info);
  return info.frame_count;
}

double hsib_web_frame_time(const hsib_sequence* s, uint32_t frame) {
  double t = 0;
  hsib_frame_info(s, frame, &t, NULL);
  return t;
}

uint32_t hsib_web_row_length(const hsib_sequence* s) {
  hsib_info info;
  hsib_get_info(s, &info);
  return info.row_length;
}

static hsib_mesh mesh_of(const hsib_sequence* s) {
  hsib_mesh m;
  hsib_get_mesh(s, &m); /* zeros for a version 1 file */
  return m;
}
uint32_t hsib_web_mesh_vertex_count(const hsib_sequence* s) { return mesh_of(s).vertex_count; }
uint32_t hsib_web_mesh_triangle_count(const hsib_sequence* s) { return mesh_of(s).triangle_count; }
const float* hsib_web_mesh_xy(const hsib_sequence* s) { return mesh_of(s).xy; }
const float* hsib_web_mesh_uv(const hsib_sequence* s) { return mesh_of(s).uv; }
const uint32_t* hsib_web_mesh_triangles(const hsib_sequence* s) { return mesh_of(s).triangles; }

/* flags: hsib_bind_flags's (HSIB_BIND_DERIVATIVES = 1 for the distortion colouring). */
hsib_binding* hsib_web_bind(const hsib_sequence* s, const float* xy, uint32_t count, uint32_t flags) {
  hsib_binding* b = NULL;
  char error[256];
  if (hsib_bind_flags(s, xy, count, 0, NULL, flags, &b, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "hsib: %s\n", error);
    return NULL;
  }
  return b;
}

void hsib_web_blend_at_time(const hsib_sequence* s, double t, int mode, hsib_blend* out) {
  *out = hsib_blend_at_time(s, t, (hsib_playback)mode);
}
