#pragma once
// Shortest decimal text that reads back to exactly the same float (text formats round-trip bit-exact).
#include <charconv>
#include <string>

namespace u3d {

inline void append_number(std::string& out, float value) {
  char buffer[32];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, end);
}

}  // namespace u3d
