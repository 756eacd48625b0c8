#pragma once
// Every failure the user can cause (bad files, bad options, bad data) is reported as u3d::Error with a
// message that names the offending file or value. The CLI prints it and exits non-zero.
#include <stdexcept>
#include <string>

namespace u3d {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws Error(message) when cond is false. For user-facing checks, not internal invariants.
inline void require(bool cond, const std::string& message) {
  if (!cond) throw Error(message);
}

}  // namespace u3d
