// hsi compare in a build without compare/ (it needs the Vulkan renderer and the
// baselines; cli/CMakeLists.txt compiles this instead of cmd_compare.cpp): the command
// exists, takes anything, and says why it cannot run, with the error exit status.
#include <stdexcept>

#include "commands.h"
#include "hsi/runtime/rendering.h"

namespace hsi::cli {

void register_compare(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("compare", "Reproduce the paper's comparisons on one scene (unavailable in this build)");
  cmd->allow_extras();
  cmd->callback([] {
    throw std::runtime_error("hsi compare cannot run: it needs compare/ (the Vulkan renderer and engine/baselines/): " +
                             runtime::rendering_unavailable_reason());
  });
}

}  // namespace hsi::cli
