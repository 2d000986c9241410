# ctest hsib_glsl: shaders/hsib_playback.glsl, the one GPU playback source, compiles
# as a vertex shader for Vulkan (SPIR-V), OpenGL 3.3 core and WebGL2 (GLSL ES 3.00),
# each time as an application writes it: version line, preamble, body, its main.
# -D: HSI_GLSLANG, HSI_SHADERS, HSI_WORK_DIR
cmake_minimum_required(VERSION 3.20)
if(NOT HSI_GLSLANG)
  message("SKIPPED: no glslangValidator")
  return()
endif()
file(REMOVE_RECURSE ${HSI_WORK_DIR})
file(READ ${HSI_SHADERS}/hsib_playback.glsl body)
file(READ ${HSI_SHADERS}/hsib_preamble_vulkan.glsl vulkan)
file(READ ${HSI_SHADERS}/hsib_preamble_gl.glsl gl)
set(main "
void main() {
  vec2 p = hsib_position(HSIB_VERTEX_INDEX);
  gl_Position = vec4(p, 0.0, 1.0);
}
")
file(WRITE ${HSI_WORK_DIR}/vulkan.vert "#version 450\n${vulkan}${body}${main}")
file(WRITE ${HSI_WORK_DIR}/gl.vert "#version 330 core\n${gl}${body}${main}")
file(WRITE ${HSI_WORK_DIR}/webgl2.vert "#version 300 es\n${gl}${body}${main}")
foreach(api vulkan gl webgl2)
  set(args -S vert)
  if(api STREQUAL "vulkan")
    list(APPEND args -V -o ${HSI_WORK_DIR}/vulkan.spv)
  endif()
  execute_process(COMMAND ${HSI_GLSLANG} ${args} ${HSI_WORK_DIR}/${api}.vert RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "hsib_playback.glsl does not compile for ${api}:\n${out}${err}")
  endif()
  message(STATUS "${api}: compiles")
endforeach()
