/* Interpolates a scene through the installed libhsi and bakes it. */
#include <hsi/hsi.h>
#include <stdio.h>

int main(int argc, char** argv) {
  if (argc != 3 || hsi_version() != HSI_VERSION) return 2;
  hsi_scene* scene = NULL;
  hsi_interpolator* interp = NULL;
  hsi_sequence* seq = NULL;
  if (hsi_scene_load_file(argv[1], &scene) || hsi_scene_set_sampling(scene, 1000, 0) ||
      hsi_interpolator_create(scene, NULL, &interp) || hsi_interpolator_sequence(interp, 3, NULL, NULL, &seq) ||
      hsi_sequence_bake_file(seq, argv[2], 1)) {
    fprintf(stderr, "consumer: %s\n", hsi_last_error());
    return 1;
  }
  printf("consumer ok: hsi %s, %u frames baked\n", hsi_version_string(), hsi_sequence_frame_count(seq));
  hsi_sequence_destroy(seq);
  hsi_interpolator_destroy(interp);
  hsi_scene_destroy(scene);
  return 0;
}
