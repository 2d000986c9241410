/* Plays a baked sequence with the standalone runtime: one vertex near the left end
 * of the shape's bounding box (inside the annulus's ring), every frame. */
#include <hsi/baked_runtime.h>
#include <stdio.h>

int main(int argc, char** argv) {
  char error[256];
  hsib_sequence* s = NULL;
  if (argc != 2 || hsib_open_file(argv[1], &s, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "player: %s\n", argc == 2 ? error : "usage: player FILE.hsib");
    return 1;
  }
  hsib_info info;
  hsib_get_info(s, &info);
  const float rest[2] = {(float)(info.bbox[0] + 0.05 * (info.bbox[2] - info.bbox[0])), (float)(0.5 * (info.bbox[1] + info.bbox[3]))};
  hsib_binding* b = NULL;
  if (hsib_bind(s, rest, 1, 0, &b, error, sizeof error) != HSIB_OK) {
    fprintf(stderr, "player: %s\n", error);
    return 1;
  }
  for (uint32_t f = 0; f < info.frame_count; ++f) {
    float out[2];
    if (hsib_evaluate(b, f, out, 0) != HSIB_OK) return 1;
    printf("frame %u: (%g, %g) -> (%g, %g)\n", f, rest[0], rest[1], out[0], out[1]);
  }
  printf("player ok: %u frames\n", info.frame_count);
  hsib_unbind(b);
  hsib_close(s);
  return 0;
}
