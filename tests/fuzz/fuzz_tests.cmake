# The short fuzz run in the test command (included from tests/CMakeLists.txt): fuzz.build builds
# the targets with clang into <build>/fuzz (tests/fuzz/CMakeLists.txt), then each target runs its
# corpus and SCATTER_FUZZ_SECONDS of mutation under ASan and UBSan; any crash, leak, hang (25 s
# per input) or sanitizer report fails the test. The long run: tests/fuzz/README.md.
find_program(SCATTER_FUZZ_CLANG clang++-14)
if(NOT SCATTER_FUZZ_CLANG)
  message(WARNING "clang++-14 not found: the fuzz tests are not added (scripts/setup installs clang)")
  return()
endif()
set(SCATTER_FUZZ_SECONDS 10 CACHE STRING "seconds of mutation per fuzz target in the test command")
set(FUZZ_SRC ${CMAKE_SOURCE_DIR}/tests/fuzz)
set(FUZZ_BUILD ${CMAKE_BINARY_DIR}/fuzz)
# fuzz_rest takes what lies beyond the parsers from this build's libraries; a gcc-sanitized build's
# would bring a second sanitizer runtime, so it is left out there.
set(FUZZ_MAIN ${CMAKE_BINARY_DIR})
if(SCATTER_SANITIZE)
  set(FUZZ_MAIN "")
endif()
add_test(NAME fuzz.build COMMAND ${FUZZ_SRC}/build.sh ${FUZZ_BUILD} ${FUZZ_MAIN})
set_tests_properties(fuzz.build PROPERTIES FIXTURES_SETUP fuzz_targets TIMEOUT 600)
set(FUZZ_TARGETS scene mesh grid json)
if(FUZZ_MAIN)
  list(APPEND FUZZ_TARGETS rest)
endif()
foreach(name ${FUZZ_TARGETS})
  add_test(NAME fuzz.${name}
           COMMAND ${FUZZ_SRC}/run.sh ${FUZZ_BUILD}/fuzz_${name} ${FUZZ_SRC}/corpus/${name}
                   ${CMAKE_CURRENT_BINARY_DIR}/tmp/fuzz_${name} ${SCATTER_FUZZ_SECONDS})
  set_tests_properties(fuzz.${name} PROPERTIES FIXTURES_REQUIRED fuzz_targets TIMEOUT 120)
endforeach()
