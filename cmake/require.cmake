# sd_require_target(TARGET DEBIAN_PACKAGE WHAT): stop configuring with a message that names the
# Debian package to install when a dependency's imported target is missing.
function(sd_require_target target package what)
  if(NOT TARGET ${target})
    message(FATAL_ERROR
      "${what} was not found. Install the Debian package '${package}' "
      "(apt-get install ${package}), or run ./scripts/demo.sh, which installs every dependency.")
  endif()
endfunction()
