# SPDX-License-Identifier: MIT
# cmake -DROOT=<repository> -DCLANG_FORMAT=<clang-format> -P FormatCheck.cmake
# Fails, naming the files, when a C++ source or header of the engine, the app or the tests
# differs from what .clang-format makes of it (docs/style.md). Test data are not sources.
file(GLOB_RECURSE files RELATIVE ${ROOT}
    ${ROOT}/engine/*.cpp ${ROOT}/engine/*.h ${ROOT}/app/*.cpp ${ROOT}/app/*.h
    ${ROOT}/tests/*.cpp ${ROOT}/tests/*.h)
list(FILTER files EXCLUDE REGEX "^tests/data/")
list(LENGTH files count)
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files}
    WORKING_DIRECTORY ${ROOT} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    string(REGEX MATCHALL "[^\n]*: error: code should be clang-formatted" lines "${err}")
    set(names)
    foreach(line IN LISTS lines)
        string(REGEX REPLACE ":[0-9]+:[0-9]+: error.*" "" name "${line}")
        list(APPEND names ${name})
    endforeach()
    list(REMOVE_DUPLICATES names)
    list(JOIN names "\n  " listed)
    message(FATAL_ERROR "clang-format: these files differ from .clang-format "
        "(run `clang-format -i` on them):\n  ${listed}")
endif()
message(STATUS "clang-format: ${count} files as .clang-format makes them")
