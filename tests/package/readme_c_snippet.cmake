# SPDX-License-Identifier: MIT
# docs_readme_c_snippet: the "C API in short" block of README.md compiles and runs as it is written.
# Extracts the first ```c block after the heading "## C API in short", puts it unchanged into the body of a
# function of a harness (readme_c_snippet_harness.c) that provides src_xyz / n_src (float64) and tgt_xyz /
# n_tgt (float32) from two point files, compiles it warning-free and runs it; the harness checks `status`
# and `result` as the snippet leaves them: KISSM_OK, a valid pose, close to the ground truth.
#
#   cmake -DREADME=README.md -DHARNESS=readme_c_snippet_harness.c -DWORK=dir -DCC=cc -DCFLAGS="..." -DINCLUDE_DIR=include
#         -DLIBS="lib;flags" -DSOURCE_CLOUD=a.ply -DTARGET_CLOUD=b.ply -DGROUND_TRUTH=gt.txt
#         -P readme_c_snippet.cmake
foreach(var README HARNESS WORK CC INCLUDE_DIR LIBS SOURCE_CLOUD TARGET_CLOUD GROUND_TRUTH)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "readme_c_snippet.cmake: -D${var}=... is missing")
  endif()
endforeach()

set(heading "## C API in short")
file(READ "${README}" readme)
string(FIND "${readme}" "\n${heading}\n" at)
if(at EQUAL -1)
  message(FATAL_ERROR "${README} has no heading '${heading}'")
endif()
string(LENGTH "\n${heading}" skip)
math(EXPR at "${at} + ${skip}")
string(SUBSTRING "${readme}" ${at} -1 rest)
string(FIND "${rest}" "\n```c\n" open)
string(FIND "${rest}" "\n## " next_heading)
if(open EQUAL -1 OR (NOT next_heading EQUAL -1 AND open GREATER next_heading))
  message(FATAL_ERROR "${README}: no ```c block under '${heading}'")
endif()
math(EXPR body_start "${open} + 6")
string(SUBSTRING "${rest}" ${body_start} -1 body)
string(FIND "${body}" "\n```" close)
if(close EQUAL -1)
  message(FATAL_ERROR "${README}: the ```c block under '${heading}' is not closed")
endif()
math(EXPR close "${close} + 1")
string(SUBSTRING "${body}" 0 ${close} snippet)
string(STRIP "${snippet}" stripped)
if(stripped STREQUAL "")
  message(FATAL_ERROR "${README}: the ```c block under '${heading}' is empty")
endif()

# README.md line of the snippet's first line, for the compiler's messages (#line).
math(EXPR before "${at} + ${body_start}")
string(SUBSTRING "${readme}" 0 ${before} head)
string(REGEX MATCHALL "\n" newlines "${head}")
list(LENGTH newlines line)
math(EXPR line "${line} + 1")

file(READ "${HARNESS}" harness)
string(FIND "${harness}" "/* KISSM_README_SNIPPET_HERE */" marker)
if(marker EQUAL -1)
  message(FATAL_ERROR "${HARNESS} has no /* KISSM_README_SNIPPET_HERE */ line")
endif()
get_filename_component(readme_path "${README}" ABSOLUTE)
string(REPLACE "/* KISSM_README_SNIPPET_HERE */" "#line ${line} \"${readme_path}\"\n${snippet}#line 1 \"after the README snippet\""
       program "${harness}")
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
file(WRITE "${WORK}/readme_snippet.c" "${program}")
message(STATUS "README.md lines ${line}.. (${close} characters) -> ${WORK}/readme_snippet.c")

separate_arguments(cflags UNIX_COMMAND "${CFLAGS}")
execute_process(
  COMMAND "${CC}" ${cflags} -std=c99 -Wall -Wextra -pedantic -Werror "-I${INCLUDE_DIR}" "${WORK}/readme_snippet.c"
          -o "${WORK}/readme_snippet" ${LIBS}
  RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the README snippet does not compile (${CC}, status ${status}): see the messages above")
endif()
execute_process(COMMAND "${WORK}/readme_snippet" "${SOURCE_CLOUD}" "${TARGET_CLOUD}" "${GROUND_TRUTH}"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the README snippet ran but failed (exit status ${status}): see the messages above")
endif()
