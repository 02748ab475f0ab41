# Writes the chapter's scene, the XML text cpp/chapter_scene.cc holds in its raw
# string kPusherSceneXml, as a C string literal in a header, so that
# bench/bare_chapter.c loads the very text sim_loop loads (one copy of it, in
# the library). Run at build time: cmake -DIN=cpp/chapter_scene.cc -DOUT=... -P this.
file(READ "${IN}" _text)
set(_open "kPusherSceneXml = R\"(")
string(FIND "${_text}" "${_open}" _begin)
if(_begin LESS 0)
  message(FATAL_ERROR "${IN}: no ${_open}...)\" to take the chapter's scene from")
endif()
string(LENGTH "${_open}" _open_length)
math(EXPR _begin "${_begin} + ${_open_length}")
string(SUBSTRING "${_text}" ${_begin} -1 _text)
string(FIND "${_text}" ")\";" _end)
string(SUBSTRING "${_text}" 0 ${_end} _xml)
string(REPLACE "\\" "\\\\" _xml "${_xml}")
string(REPLACE "\"" "\\\"" _xml "${_xml}")
string(REPLACE "\n" "\\n\"\n    \"" _xml "${_xml}")
file(WRITE "${OUT}.tmp" "/* Generated from ${IN} by cmake/SceneXmlHeader.cmake: do not edit. */\n"
                        "static const char kPusherSceneXml[] =\n    \"${_xml}\";\n")
# Only a changed text touches the header (and rebuilds what includes it).
configure_file("${OUT}.tmp" "${OUT}" COPYONLY)
file(REMOVE "${OUT}.tmp")
