/* hsi C API example: only hsi/hsi.h. Loads a scene, interpolates it, prints the
 * report, evaluates every frame's map at the scene's handles (stand-ins for a game
 * mesh's vertices), bakes the sequence, then authors two keyframes of its own on a
 * shape given as JSON text and interpolates those.
 *
 *   hsi_example SCENE OUT_DIR [FRAMES [SAMPLES [BACKEND]]]
 *
 * BACKEND: cpu (default), auto or cuda: the Newton core that solves the frames (auto
 * takes a CUDA GPU where this library has CUDA and one is present, and says why not).
 *
 * Writes OUT_DIR/points.txt ("frame t certified x0 y0 x1 y1 ..." per frame, the
 * handles' images), OUT_DIR/report.json, OUT_DIR/sequence.hsib and, where the
 * library renders, OUT_DIR/frame.ppm. Exits non-zero on any error. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hsi/hsi.h"

#define CHECK(call)                                                                        \
  do {                                                                                     \
    hsi_status status_ = (call);                                                           \
    if (status_ != HSI_OK) {                                                               \
      fprintf(stderr, "hsi_example: %s failed: %s: %s\n", #call, hsi_status_name(status_), \
              hsi_last_error());                                                           \
      return 1;                                                                            \
    }                                                                                      \
  } while (0)

static int on_frame(uint32_t frame, uint32_t count, const hsi_frame_report* r, void* user) {
  (void)user;
  printf("  frame %u/%u  t = %.4f  %d iterations  %s%s%s", frame + 1, count, r->t, r->iterations,
         r->certified ? "certified locally injective" : "NOT CERTIFIED", r->converged ? "" : ", NOT CONVERGED",
         r->overlaps ? ", OVERLAPS ITSELF" : "");
  /* Sampled distortion, and what the certificate proves (NaN when not certified). */
  printf("  sigma1 %.4f sampled, <= %.4f certified\n", r->sigma1_max, r->certified_sigma1_max);
  return 0; /* non-zero would cancel */
}

static int write_text(const char* dir, const char* name, const char* text, size_t size) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE* f = fopen(path, "wb");
  if (!f || fwrite(text, 1, size, f) != size) {
    fprintf(stderr, "hsi_example: cannot write %s\n", path);
    if (f) fclose(f);
    return 1;
  }
  fclose(f);
  return 0;
}

/* Part 2: a shape from JSON text (a square with a square hole), two handles, two
 * keyframes authored by dragging them, and three frames in between. */
static int author_and_interpolate(uint32_t samples) {
  const char* json =
      "{ \"hsi_scene\": 1, \"name\": \"frame\","
      "  \"shape\": { \"outer\": [[0,0],[4,0],[4,4],[0,4]], \"holes\": [[[1.5,1.5],[2.5,1.5],[2.5,2.5],[1.5,2.5]]] } }";
  hsi_scene* scene = NULL;
  CHECK(hsi_scene_load_memory(json, strlen(json), NULL, &scene));
  CHECK(hsi_scene_set_sampling(scene, samples, 0));
  const double handles[] = {0.5, 0.5, 3.5, 0.5, 3.5, 3.5, 0.5, 3.5};
  CHECK(hsi_scene_set_handles(scene, handles, 4));
  const double stretched[] = {0.5, 0.5, 3.5, 0.5, 3.9, 3.5, 0.9, 3.5}; /* the top slides right */
  hsi_keyframe_report k;
  CHECK(hsi_scene_add_keyframe(scene, 0.0, handles, 4, &k));
  CHECK(hsi_scene_add_keyframe(scene, 1.0, stretched, 4, &k));
  printf("authored keyframe: certified %d, reached %d, max target error %.2e, %d iterations\n", k.certified, k.reached,
         k.max_target_error, k.iterations);
  hsi_interpolator* interp = NULL;
  CHECK(hsi_interpolator_create(scene, NULL, &interp));
  hsi_scene_destroy(scene); /* the interpolator keeps what it needs */
  hsi_sequence* mid = NULL;
  CHECK(hsi_interpolator_frame(interp, 0.5, &mid));
  hsi_frame_report r;
  CHECK(hsi_sequence_frame_report(mid, 0, &r));
  const double p[2] = {3.5, 3.5};
  double q[2];
  CHECK(hsi_sequence_evaluate(mid, 0, p, 1, q));
  printf("authored scene at t = 0.5: %s, handle 2 at (%.4f, %.4f)\n", r.certified ? "certified" : "NOT CERTIFIED", q[0], q[1]);
  hsi_sequence_destroy(mid);
  hsi_interpolator_destroy(interp);
  return r.certified ? 0 : 1;
}

int main(int argc, char** argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s SCENE OUT_DIR [FRAMES [SAMPLES [cpu|auto|cuda]]]\n", argv[0]);
    return 2;
  }
  const char* out_dir = argv[2];
  const uint32_t frames = argc > 3 ? (uint32_t)strtoul(argv[3], NULL, 10) : 9;
  const uint32_t samples = argc > 4 ? (uint32_t)strtoul(argv[4], NULL, 10) : 0;
  hsi_interpolation_options options;
  hsi_interpolation_options_default(&options);
  if (argc > 5) {
    const hsi_backend all[] = {HSI_BACKEND_CPU, HSI_BACKEND_AUTO, HSI_BACKEND_CUDA};
    int found = 0;
    for (int b = 0; b < 3; ++b)
      if (strcmp(argv[5], hsi_backend_name(all[b])) == 0) {
        options.backend = all[b];
        found = 1;
      }
    if (!found) {
      fprintf(stderr, "hsi_example: backend '%s' is not cpu, auto or cuda\n", argv[5]);
      return 2;
    }
  }
  printf("hsi %s (header %s)\n", hsi_version_string(), HSI_VERSION_STRING);
  if (hsi_version() / 100 != HSI_VERSION / 100) {
    fprintf(stderr, "hsi_example: library %s does not match the header %s\n", hsi_version_string(), HSI_VERSION_STRING);
    return 1;
  }

  hsi_scene* scene = NULL;
  CHECK(hsi_scene_load_file(argv[1], &scene));
  CHECK(hsi_scene_set_sampling(scene, samples, 0));
  hsi_scene_info info;
  CHECK(hsi_scene_get_info(scene, &info));
  printf("scene: %u loops, cage %u vertices, %u handles, %u keyframes, |G| = %u, size %.4g\n", info.loop_count,
         info.cage_vertex_count, info.handle_count, info.keyframe_count, info.samples, info.size);

  hsi_interpolator* interp = NULL;
  CHECK(hsi_interpolator_create(scene, &options, &interp));
  hsi_backend_info backend;
  CHECK(hsi_interpolator_backend(interp, &backend));
  printf("Newton core: %s", hsi_backend_name(backend.used));
  if (backend.device[0]) printf(" on %s", backend.device);
  if (backend.fallback[0]) printf(" (auto: CUDA not used: %s)", backend.fallback);
  printf("\n");
  hsi_sequence* seq = NULL;
  CHECK(hsi_interpolator_sequence(interp, frames, on_frame, NULL, &seq));
  hsi_sequence_summary sum;
  CHECK(hsi_sequence_summary_get(seq, &sum));
  printf("%u frames, %u certified locally injective, %u not converged, %u overlapping themselves, mean %.2f iterations, "
         "%.1f ms per frame\n",
         sum.frames, sum.certified, sum.not_converged, sum.overlapping, sum.mean_iterations, sum.mean_ms);

  /* Every frame's map at the handles. */
  double* handles = (double*)malloc(2 * (info.handle_count + 1) * sizeof(double));
  double* moved = (double*)malloc(2 * (info.handle_count + 1) * sizeof(double));
  uint32_t handle_count = 0;
  CHECK(hsi_scene_get_handles(scene, handles, info.handle_count, &handle_count));
  char path[1024];
  snprintf(path, sizeof path, "%s/points.txt", out_dir);
  FILE* pts = fopen(path, "w");
  if (!pts) {
    fprintf(stderr, "hsi_example: cannot write %s\n", path);
    return 1;
  }
  for (uint32_t f = 0; f < hsi_sequence_frame_count(seq); ++f) {
    hsi_frame_report r;
    CHECK(hsi_sequence_frame_report(seq, f, &r));
    CHECK(hsi_sequence_evaluate(seq, f, handles, handle_count, moved));
    fprintf(pts, "%u %.17g %d", f, r.t, r.certified);
    for (uint32_t h = 0; h < 2 * handle_count; ++h) fprintf(pts, " %.17g", moved[h]);
    fprintf(pts, "\n");
  }
  fclose(pts);
  free(handles);
  free(moved);

  /* The report, through the two-call buffer protocol. */
  size_t length = 0;
  if (hsi_sequence_report_json(seq, NULL, 0, &length) != HSI_ERROR_BUFFER_TOO_SMALL) return 1;
  char* json = (char*)malloc(length + 1);
  CHECK(hsi_sequence_report_json(seq, json, length + 1, &length));
  if (write_text(out_dir, "report.json", json, length)) return 1;
  free(json);

  snprintf(path, sizeof path, "%s/sequence.hsib", out_dir);
  CHECK(hsi_sequence_bake_file(seq, path, 1));

  const char* why = NULL;
  if (hsi_render_available(&why)) {
    hsi_render_options ro;
    hsi_render_options_default(&ro);
    ro.width = ro.height = 128;
    unsigned char* rgba = (unsigned char*)malloc(4u * ro.width * ro.height);
    CHECK(hsi_sequence_render(seq, frames / 2, &ro, rgba, 0));
    snprintf(path, sizeof path, "%s/frame.ppm", out_dir);
    FILE* ppm = fopen(path, "wb");
    if (!ppm) return 1;
    fprintf(ppm, "P6\n%u %u\n255\n", ro.width, ro.height);
    for (uint32_t i = 0; i < ro.width * ro.height; ++i) fwrite(rgba + 4 * i, 1, 3, ppm);
    fclose(ppm);
    free(rgba);
    printf("rendered frame %u to %s\n", frames / 2, path);
  } else {
    printf("no rendering: %s\n", why);
  }

  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(interp);
  hsi_scene_destroy(scene);

  /* Errors are codes plus a message, never a crash. */
  hsi_scene* missing = NULL;
  const hsi_status s = hsi_scene_load_file("/no/such/scene.json", &missing);
  printf("loading a missing file: %s: %s\n", hsi_status_name(s), hsi_last_error());
  if (s != HSI_ERROR_IO || missing != NULL) return 1;

  return author_and_interpolate(samples);
}
