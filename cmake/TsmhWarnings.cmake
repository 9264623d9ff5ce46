# tsmh::warnings: the warning set every target of ours links privately.
add_library(tsmh_warnings INTERFACE)
add_library(tsmh::warnings ALIAS tsmh_warnings)
target_compile_options(tsmh_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough>
  $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic>
  $<$<BOOL:${TSMH_WERROR}>:-Werror>)
