# Shared by CLI tests that edit a scene file (cmake -P scripts):
#   include(${CMAKE_CURRENT_LIST_DIR}/scene_json.cmake)

# small_scene(OUT_VAR SCENE_FILE SAMPLES): the scene's JSON text with |G| = SAMPLES and
# its texture named by absolute path, so that the text can be written anywhere.
function(small_scene out scene samples)
  file(READ ${scene} text)
  get_filename_component(dir ${scene} DIRECTORY)
  string(JSON texture ERROR_VARIABLE no_texture GET "${text}" texture)
  if(NOT no_texture)
    string(JSON text SET "${text}" texture "\"${dir}/${texture}\"")
  endif()
  string(JSON text SET "${text}" samples ${samples})
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# reversed_array(OUT_VAR JSON_TEXT MEMBER...): the JSON array at that member path,
# its elements in the other order.
function(reversed_array out text)
  string(JSON n LENGTH "${text}" ${ARGN})
  math(EXPR last "${n} - 1")
  set(reversed "")
  foreach(i RANGE ${last})
    math(EXPR j "${last} - ${i}")
    string(JSON p GET "${text}" ${ARGN} ${j})
    string(APPEND reversed ",${p}")
  endforeach()
  string(SUBSTRING "${reversed}" 1 -1 reversed)
  set(${out} "[${reversed}]" PARENT_SCOPE)
endfunction()

# reverse_shape_loops(OUT_VAR JSON_TEXT): the same scene with every loop of its shape
# (shape.outer, each of shape.holes) listed the other way round.
function(reverse_shape_loops out text)
  reversed_array(loop "${text}" shape outer)
  string(JSON text SET "${text}" shape outer "${loop}")
  string(JSON holes ERROR_VARIABLE no_holes LENGTH "${text}" shape holes)
  if(NOT no_holes AND holes GREATER 0)
    math(EXPR last_hole "${holes} - 1")
    foreach(h RANGE ${last_hole})
      reversed_array(loop "${text}" shape holes ${h})
      string(JSON text SET "${text}" shape holes ${h} "${loop}")
    endforeach()
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()
