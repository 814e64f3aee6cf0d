#include <charconv>
#include <stdexcept>

#include <fmt/format.h>

#include "app/commands.h"

namespace raylab::cli {

namespace {
bool parse_positive(const std::string& s, int& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size() && v > 0;
}
}  // namespace

std::pair<int, int> parse_size(const std::string& text) {
  const auto x = text.find('x');
  int w = 0, h = 0;
  if (x == std::string::npos || !parse_positive(text.substr(0, x), w) || !parse_positive(text.substr(x + 1), h) ||
      w > 65536 || h > 65536)
    throw std::invalid_argument(fmt::format("invalid size '{}' (expected WIDTHxHEIGHT, e.g. 512x512)", text));
  return {w, h};
}

std::vector<std::string> parse_name_list(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::vector<int> parse_int_list(const std::string& text, const char* what) {
  std::vector<int> out;
  for (const auto& item : parse_name_list(text)) {
    int v = 0;
    if (!parse_positive(item, v)) throw std::invalid_argument(fmt::format("invalid {} '{}' (expected positive integers)", what, item));
    out.push_back(v);
  }
  if (out.empty()) throw std::invalid_argument(fmt::format("no {} given", what));
  return out;
}

}  // namespace raylab::cli
