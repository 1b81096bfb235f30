#pragma once
// Invariant checks inside the library (pbrt-v4's habit), in two levels:
//   SD_CHECK(cond, what)   always on: cheap checks whose failure means a bug, not bad input;
//   SD_DCHECK(cond, what)  debug builds only (NDEBUG unset): expensive checks, such as a whole
//                          mesh's validate() after each change.
// A failed check throws sd::InvariantError naming the file, the line, the condition and `what`;
// the library never calls exit() or abort(). Bad input from a user is not an invariant: it gets
// its own typed error with a sentence a designer can act on.

#include <stdexcept>
#include <string>

namespace sd {

class InvariantError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace detail {
[[noreturn]] inline void check_failed(const char* file, int line, const char* condition,
                                      const std::string& what) {
  std::string message = std::string(file) + ":" + std::to_string(line) + ": internal check '" +
                        condition + "' failed";
  if (!what.empty()) message += ": " + what;
  throw InvariantError(message);
}
}  // namespace detail

}  // namespace sd

#define SD_CHECK(condition, what)                                                         \
  do {                                                                                    \
    if (!(condition)) ::sd::detail::check_failed(__FILE__, __LINE__, #condition, (what)); \
  } while (false)

#ifdef NDEBUG
#define SD_DCHECK(condition, what) \
  do {                             \
  } while (false)
#else
#define SD_DCHECK(condition, what) SD_CHECK(condition, what)
#endif
