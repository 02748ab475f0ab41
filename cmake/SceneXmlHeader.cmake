# Writes the chapter's scene, the XML text cpp/chapter_scene.cc holds in its
# raw string kPusherSceneXml, as a C string literal in a header, so that
# bench/bare_chapter.c loads the very text sim_loop loads (one copy of it, in
# the library). Run at build time: cmake -DIN=cpp/chapter_scene.cc -DOUT=... -P this.
include(${CMAKE_CURRENT_LIST_DIR}/TakeBlock.cmake)
simloop_take_block("${IN}" "kPusherSceneXml = R\"(" ")\";" _xml)
string(REPLACE "\\" "\\\\" _xml "${_xml}")
string(REPLACE "\"" "\\\"" _xml "${_xml}")
string(REPLACE "\n" "\\n\"\n    \"" _xml "${_xml}")
simloop_write_if_changed("${OUT}" "/* Generated from ${IN} by cmake/SceneXmlHeader.cmake: do not edit. */
static const char kPusherSceneXml[] =\n    \"${_xml}\";\n")
