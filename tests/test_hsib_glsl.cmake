# ctest hsib_glsl: shaders/hsib_playback.glsl, the one GPU playback source, compiles
# as a vertex shader for Vulkan (SPIR-V), OpenGL 3.3 core and WebGL2 (GLSL ES 3.00),
# each time as an application writes it: version line, preamble, body, its main;
# once for positions only and once with HSIB_DERIVATIVES (hsib_jacobian,
# hsib_singular_values and the distortion measures).
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
# The distortion variant: derivative rows bound too; sigma1, sigma2 and the measures
# feed the output, so that no call is optimised away.
set(main_sigma "
void main() {
  vec2 p = hsib_position(HSIB_VERTEX_INDEX);
  mat2 J = hsib_jacobian(HSIB_VERTEX_INDEX);
  vec2 sigma = hsib_singular_values(HSIB_VERTEX_INDEX);
  float isometric = hsib_isometric_distortion(hsib_singular_values_of(J));
  float conformal = hsib_conformal_distortion(sigma);
  gl_Position = vec4(p, sigma.x - sigma.y, isometric + conformal);
}
")
set(sigma_define "#define HSIB_DERIVATIVES\n")
file(WRITE ${HSI_WORK_DIR}/vulkan.vert "#version 450\n${vulkan}${body}${main}")
file(WRITE ${HSI_WORK_DIR}/gl.vert "#version 330 core\n${gl}${body}${main}")
file(WRITE ${HSI_WORK_DIR}/webgl2.vert "#version 300 es\n${gl}${body}${main}")
file(WRITE ${HSI_WORK_DIR}/vulkan_sigma.vert "#version 450\n${sigma_define}${vulkan}${body}${main_sigma}")
file(WRITE ${HSI_WORK_DIR}/gl_sigma.vert "#version 330 core\n${sigma_define}${gl}${body}${main_sigma}")
file(WRITE ${HSI_WORK_DIR}/webgl2_sigma.vert "#version 300 es\n${sigma_define}${gl}${body}${main_sigma}")
foreach(api vulkan gl webgl2 vulkan_sigma gl_sigma webgl2_sigma)
  set(args -S vert)
  if(api MATCHES "^vulkan")
    list(APPEND args -V -o ${HSI_WORK_DIR}/${api}.spv)
  endif()
  execute_process(COMMAND ${HSI_GLSLANG} ${args} ${HSI_WORK_DIR}/${api}.vert RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "hsib_playback.glsl does not compile for ${api}:\n${out}${err}")
  endif()
  message(STATUS "${api}: compiles")
endforeach()
