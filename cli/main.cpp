// hsi: harmonic shape interpolation of 2D shapes with holes, from the command line.
#include <cstdio>
#include <exception>

#include "commands.h"
#include "hsi/domain.h"

int main(int argc, char** argv) {
  CLI::App app{
      "hsi - harmonic shape interpolation of 2D shapes with holes (Shi & Chen, SGP 2022).\n"
      "Every frame is a harmonic map of the shape, certified locally injective.\n"
      "Run 'hsi <command> --help' for the options of a command.\n"
      "Exit status: 0 ok; 1 error; 2 bad input; interpolate, bake, export: 3 some frame not certified,\n"
      "4 some frame did not converge (see their --help); keyframes: 5 some handle target not reached."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "hsi 0.1.0");
  hsi::cli::register_info(app);
  hsi::cli::register_import_png(app);
  hsi::cli::register_import_glyph(app);
  hsi::cli::register_keyframes(app);
  hsi::cli::register_eval(app);
  hsi::cli::register_interpolate(app);
  hsi::cli::register_bake(app);
  hsi::cli::register_export(app);
  hsi::cli::register_render(app);
  hsi::cli::register_compare(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const hsi::cli::FlaggedFrames& e) {
    std::fprintf(stderr, "hsi: %s: %s\n", e.status == hsi::cli::kExitNotConverged ? "warning" : "error", e.what());
    return e.status;
  } catch (const hsi::InputError& e) {
    std::fprintf(stderr, "hsi: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hsi: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
