# simloop_take_block(FILE OPEN CLOSE VAR): VAR = the text in FILE between the
# first OPEN and the CLOSE after it (a fatal error naming FILE if there is no
# OPEN). What the build takes from the sources into generated files, so that
# there is one copy of each text: the chapter's scene, the README's example.
function(simloop_take_block file open close var)
  file(READ "${file}" _text)
  string(FIND "${_text}" "${open}" _begin)
  if(_begin LESS 0)
    message(FATAL_ERROR "${file}: no ${open}...${close} to take")
  endif()
  string(LENGTH "${open}" _open_length)
  math(EXPR _begin "${_begin} + ${_open_length}")
  string(SUBSTRING "${_text}" ${_begin} -1 _text)
  string(FIND "${_text}" "${close}" _end)
  string(SUBSTRING "${_text}" 0 ${_end} _block)
  set(${var} "${_block}" PARENT_SCOPE)
endfunction()

# Writes TEXT to OUT, touching OUT only when the text changed (so that only
# a changed text rebuilds what uses it).
function(simloop_write_if_changed out text)
  file(WRITE "${out}.tmp" "${text}")
  configure_file("${out}.tmp" "${out}" COPYONLY)
  file(REMOVE "${out}.tmp")
endfunction()
