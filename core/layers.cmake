# lumistage_read_layers(TABLE): reads core/layers.txt (what it says: see there) and sets, in the
# caller's scope,
#   LUMISTAGE_LAYERS               the folders of core/, from the ground up;
#   LUMISTAGE_LAYER_USES_<folder>  the folders on <folder>'s line;
#   LUMISTAGE_LAYER_LINE_<folder>  the number of that line.
# It fails, naming the line and what to do, on a line it cannot read, a folder on two lines, or a
# line naming a folder that is not on a line above it. Used by core/CMakeLists.txt (the link
# lists) and core/check_layers.cmake (the include check), so that the table is read one way.
function(lumistage_read_layers table)
  get_filename_component(name "${table}" NAME)
  set(name "core/${name}")  # for the messages: the table is core/'s
  file(READ "${table}" text)
  string(REPLACE ";" "," text "${text}")  # a CMake list separator; only comments hold one
  string(REPLACE "\n" ";" lines "${text}")
  set(number 0)
  set(folders "")
  set(errors "")
  foreach(line IN LISTS lines)
    math(EXPR number "${number} + 1")
    string(REGEX REPLACE "#.*" "" line "${line}")
    string(STRIP "${line}" line)
    if(line STREQUAL "")
      continue()
    endif()
    if(NOT line MATCHES "^([a-z0-9_]+):(.*)$")
      list(APPEND errors "${name}:${number}: \"${line}\" is not \"folder: the folders it uses\"")
      continue()
    endif()
    set(folder ${CMAKE_MATCH_1})
    string(REGEX MATCHALL "[^ \t]+" uses "${CMAKE_MATCH_2}")
    if(folder IN_LIST folders)
      list(APPEND errors "${name}:${number}: ${folder} has a line already (line \
${line_${folder}}): give each folder one line")
      continue()
    endif()
    list(APPEND folders ${folder})
    set(line_${folder} ${number})
    set(uses_${folder} ${uses})
  endforeach()

  foreach(folder IN LISTS folders)
    foreach(used IN LISTS uses_${folder})
      list(FIND folders ${used} used_at)
      list(FIND folders ${folder} folder_at)
      if(used_at LESS 0)
        list(APPEND errors "${name}:${line_${folder}}: ${folder} names ${used}, which has no \
line: name only folders of core/ that are on a line above it")
      elseif(used_at GREATER_EQUAL folder_at)
        list(APPEND errors "${name}:${line_${folder}}: ${folder} names ${used}, which is not \
below it: a folder uses only the folders on the lines above it. Move the code ${folder} needs \
from core/${used}/ down into core/${folder}/ or a folder below it")
      endif()
    endforeach()
  endforeach()

  if(errors)
    list(JOIN errors "\n" errors)
    message(FATAL_ERROR "${name} breaks its own rule:\n${errors}")
  endif()
  set(LUMISTAGE_LAYERS ${folders} PARENT_SCOPE)
  foreach(folder IN LISTS folders)
    set(LUMISTAGE_LAYER_USES_${folder} ${uses_${folder}} PARENT_SCOPE)
    set(LUMISTAGE_LAYER_LINE_${folder} ${line_${folder}} PARENT_SCOPE)
  endforeach()
endfunction()
