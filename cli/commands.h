// Subcommands of the hsi tool. Each registers itself on the app and runs from
// its callback; errors surface as exceptions that main() turns into a message.
#pragma once

#include <CLI/CLI.hpp>

namespace hsi::cli {

void register_info(CLI::App& app);
void register_import_png(CLI::App& app);
void register_import_glyph(CLI::App& app);
void register_keyframes(CLI::App& app);
void register_interpolate(CLI::App& app);
void register_bake(CLI::App& app);
void register_export(CLI::App& app);
void register_render(CLI::App& app);
void register_compare(CLI::App& app);

}  // namespace hsi::cli
