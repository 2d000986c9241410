// hsi render in a build without the Vulkan renderer (cli/CMakeLists.txt compiles this
// instead of cmd_render.cpp): the command exists, takes anything, and says why it
// cannot run (runtime/'s reason), with the error exit status.
#include <stdexcept>

#include "commands.h"
#include "hsi/runtime/rendering.h"

namespace hsi::cli {

void register_render(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("render", kRenderHelp);
  cmd->allow_extras();
  cmd->callback([] { throw std::runtime_error("hsi render cannot run: " + runtime::rendering_unavailable_reason()); });
}

}  // namespace hsi::cli
