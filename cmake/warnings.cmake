# sd_warnings: the project's warning flags, linked PRIVATE by every target we build.
add_library(sd_warnings INTERFACE)
target_compile_options(sd_warnings INTERFACE -Wall -Wextra -Wpedantic
                                             $<$<CXX_COMPILER_ID:GNU>:-Wshadow=local>
                                             -Wno-deprecated-declarations
                                             # GCC 12 false positives on std::string operator+ (GCC bug 105329)
                                             $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>)
if(SD_WERROR)
  target_compile_options(sd_warnings INTERFACE -Werror)
endif()
