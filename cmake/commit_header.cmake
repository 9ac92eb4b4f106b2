# Writes OUT, a header defining DYNSKY_COMMIT: the commit the sources are at, "-dirty" added when
# tracked files differ from it, "" outside git. Run at every build (util/CMakeLists.txt), the
# header rewritten only when it changes: `dynsky --version` and the Software field of every image
# written name the build that made them (the commit was once taken at configure time and went stale).
execute_process(COMMAND git -C "${SRC}" rev-parse --short HEAD OUTPUT_VARIABLE commit
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
# Only the sources' own repository: a tarball unpacked inside another checkout is not at its commit.
execute_process(COMMAND git -C "${SRC}" rev-parse --show-toplevel OUTPUT_VARIABLE top
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
get_filename_component(top "${top}" REALPATH)
get_filename_component(src "${SRC}" REALPATH)
if(failed OR NOT top STREQUAL src)
  set(commit "")
endif()
if(commit)
  execute_process(COMMAND git -C "${SRC}" diff --quiet HEAD -- RESULT_VARIABLE dirty ERROR_QUIET)
  if(dirty EQUAL 1)
    set(commit "${commit}-dirty")
  endif()
endif()
file(WRITE "${OUT}.tmp" "#define DYNSKY_COMMIT \"${commit}\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUT}.tmp" "${OUT}")
file(REMOVE "${OUT}.tmp")
