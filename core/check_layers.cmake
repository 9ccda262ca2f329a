# The include check of core/'s layers: the test core_layers, or by hand from anywhere:
#   cmake -P core/check_layers.cmake
# Reads every #include of every file of core/<folder>/ and fails, naming the file, the line and
# what to do, when
# - it includes core/<other>/ and <other> is not on <folder>'s line in core/layers.txt (above it:
#   an include that runs back up; below it but not named: a use the link lists do not know);
# - it includes a header of core/ by a relative path (../), or anything of app/, ui/ or tests/;
# - <folder>'s line names a folder that no file of <folder> includes any more;
# - a folder of core/ has no line in core/layers.txt, or a line names no folder of core/.
# The links cannot catch what this does: a header-only use of another folder (its inline
# functions, types and templates) compiles through the include root all of core/ shares.
cmake_minimum_required(VERSION 3.25)
get_filename_component(root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
include(${CMAKE_CURRENT_LIST_DIR}/layers.cmake)
lumistage_read_layers(${root}/core/layers.txt)

set(problems "")
# The line of FILE that holds TEXT, into VAR.
function(line_of file text var)
  file(READ "${root}/${file}" content)
  string(FIND "${content}" "${text}" at)
  string(SUBSTRING "${content}" 0 ${at} before)
  string(LENGTH "${before}" with)
  string(REPLACE "\n" "" before "${before}")
  string(LENGTH "${before}" without)
  math(EXPR line "${with} - ${without} + 1")
  set(${var} ${line} PARENT_SCOPE)
endfunction()

file(GLOB entries LIST_DIRECTORIES true RELATIVE ${root}/core ${root}/core/*)
foreach(entry IN LISTS entries)
  if(IS_DIRECTORY ${root}/core/${entry} AND NOT entry IN_LIST LUMISTAGE_LAYERS)
    list(APPEND problems "core/${entry}/ has no line in core/layers.txt. Add one where it belongs \
in the order (above every folder it includes), naming those folders, and give core/${entry}/ a \
CMakeLists.txt that calls lumistage_core_folder(${entry} <its .cpp files>).")
  endif()
endforeach()

set(checked 0)
foreach(folder IN LISTS LUMISTAGE_LAYERS)
  set(table_line "core/layers.txt:${LUMISTAGE_LAYER_LINE_${folder}}")
  set(uses ${LUMISTAGE_LAYER_USES_${folder}})
  string(JOIN " " uses_text ${uses})
  if(NOT IS_DIRECTORY ${root}/core/${folder})
    list(APPEND problems "${table_line}: core/${folder}/ does not exist. Take its line out.")
    continue()
  endif()
  list(FIND LUMISTAGE_LAYERS ${folder} folder_at)
  set(included "")
  file(GLOB_RECURSE files RELATIVE ${root} ${root}/core/${folder}/*)
  list(FILTER files INCLUDE REGEX "\\.(h|hh|hpp|c|cc|cpp|cxx|inl|ipp)$")
  foreach(file IN LISTS files)
    math(EXPR checked "${checked} + 1")
    file(STRINGS ${root}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]")
    foreach(include IN LISTS includes)
      string(REGEX MATCH "[\"<]([^\">]*)[\">]" quoted "${include}")
      set(path "${CMAKE_MATCH_1}")
      set(problem "")
      if(path MATCHES "(^|/)\\.\\./")
        set(problem "a header by a relative path. Name a header of core/ by its path from the \
repository root: \"core/<folder>/<file>\".")
      elseif(path MATCHES "^(app|ui|tests)/")
        set(problem "nothing of core/ includes app/, ui/ or tests/: they are built on core/. \
Move what core/${folder}/ needs from there into core/.")
      elseif(path MATCHES "^core/([^/]+)/")
        set(used ${CMAKE_MATCH_1})
        list(FIND LUMISTAGE_LAYERS ${used} used_at)
        if(used STREQUAL folder)
        elseif(used IN_LIST uses)
          list(APPEND included ${used})
        elseif(used_at LESS 0)
          set(problem "core/${used}/ has no line in core/layers.txt: no such folder of core/. \
Include a header of core/ by its path from the repository root: \"core/<folder>/<file>\".")
        elseif(used_at GREATER folder_at)
          set(problem "${used} is above ${folder} in core/layers.txt (line \
${LUMISTAGE_LAYER_LINE_${used}}, ${folder} on line ${LUMISTAGE_LAYER_LINE_${folder}}): an include \
that runs back up. Move what core/${folder}/ needs from core/${used}/ down into core/${folder}/ or \
a folder below it (or this file up into core/${used}/ or above). Never reorder core/layers.txt to \
make room.")
        else()
          set(problem "${used} is below ${folder} but not on ${folder}'s line (${table_line}: \
\"${folder}: ${uses_text}\"). If ${folder} is to use ${used}, add ${used} to that line: \
lumistage_${folder} then links lumistage_${used} too.")
        endif()
      endif()
      if(problem)
        line_of(${file} "${include}" line)
        list(APPEND problems "${file}:${line}: #include ${quoted}: ${problem}")
      endif()
    endforeach()
  endforeach()
  foreach(used IN LISTS uses)
    if(NOT used IN_LIST included)
      list(APPEND problems "${table_line}: ${folder}'s line names ${used}, but no file of \
core/${folder}/ includes core/${used}/ any more. Take ${used} off that line, so that \
lumistage_${folder} no longer links lumistage_${used}.")
    endif()
  endforeach()
endforeach()

list(LENGTH problems count)
if(count GREATER 0)
  foreach(problem IN LISTS problems)
    message(NOTICE "${problem}")
  endforeach()
  message(NOTICE "${count} problem(s) with core/'s layers, above. The rule is core/layers.txt: a \
folder of core/ includes core/ only from itself and the folders on its line, each below it \
(docs/architecture.md, \"Layout, style and tests\").")
  message(FATAL_ERROR "core/'s layers do not hold")
endif()
list(LENGTH LUMISTAGE_LAYERS folders)
message(STATUS "core/'s layers hold: ${checked} files in ${folders} folders, every include of \
core/ allowed by core/layers.txt")
