# SPDX-License-Identifier: MIT
# cmake -DOUT=<header> -DSRC_DIR=<dir> -DFILES=<a,b> -P EmbedShaders.cmake
# Writes one `inline constexpr char NAME[]` raw string per shader (surface.frag → SURFACE_FRAG).
set(text "// Generated from app/gui/shaders by EmbedShaders.cmake. Do not edit.\n#pragma once\n")
string(APPEND text "namespace lucent::app::shaders {\n")
string(REPLACE "," ";" FILES "${FILES}")
foreach(f IN LISTS FILES)
    file(READ ${SRC_DIR}/${f} body)
    get_filename_component(name ${f} NAME)
    string(TOUPPER ${name} id)
    string(REPLACE "." "_" id ${id})
    string(APPEND text "inline constexpr char ${id}[] = R\"lucentglsl(${body})lucentglsl\";\n")
endforeach()
string(APPEND text "}  // namespace lucent::app::shaders\n")
file(WRITE ${OUT}.tmp "${text}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
