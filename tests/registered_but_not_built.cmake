# ctest `registered_test_programs_are_built` (tests/CMakeLists.txt): LIST names the test programs
# whose tests are registered although the default build leaves them out (EXCLUDE_FROM_ALL). Each
# would show up in a plain `ctest` as a failing <program>_NOT_BUILT placeholder.
file(STRINGS ${LIST} programs)
if(programs)
  string(REPLACE ";" ", " programs "${programs}")
  message(FATAL_ERROR "registered tests of programs the default build leaves out: ${programs}; "
                      "register them only when they are built (IMPLICIT_SLOW_TESTS)")
endif()
message(STATUS "every registered test program is part of the default build")
