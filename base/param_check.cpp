#include "base/param_check.h"

#include <charconv>
#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace raylab {

namespace {

// Whole numbers print without a fraction (1048576, not 1.048576e+06).
std::string number_text(double x) {
  if (std::floor(x) == x && std::fabs(x) < 1e15) return fmt::format("{}", static_cast<long long>(x));
  return fmt::format("{}", x);
}

// "a", "a or b", "a, b or c".
std::string alternatives(const std::vector<std::string>& parts) {
  std::string s;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) s += i + 1 == parts.size() ? " or " : ", ";
    s += parts[i];
  }
  return s;
}

bool low_open(Ends e) { return e == Ends::OpenLow || e == Ends::Open; }
bool high_open(Ends e) { return e == Ends::OpenHigh || e == Ends::Open; }

std::string range_text(const ParamCheck& c) {
  const bool lo_open = c.kind == ParamKind::Real && low_open(c.ends);
  const bool hi_open = c.kind == ParamKind::Real && high_open(c.ends);
  if (std::isinf(c.lo) && std::isinf(c.hi)) return c.kind == ParamKind::Integer ? "a whole number" : "a number";
  if (std::isinf(c.hi)) return (lo_open ? "> " : ">= ") + number_text(c.lo);
  if (std::isinf(c.lo)) return (hi_open ? "< " : "<= ") + number_text(c.hi);
  if (c.kind == ParamKind::Integer) return "in " + number_text(c.lo) + ".." + number_text(c.hi);
  return fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", number_text(c.lo), number_text(c.hi), hi_open ? ")" : "]");
}

bool in_range(const ParamCheck& c, double v) {
  if (!c.has_range) return false;
  const bool lo_open = c.kind == ParamKind::Real && low_open(c.ends);
  const bool hi_open = c.kind == ParamKind::Real && high_open(c.ends);
  return (lo_open ? v > c.lo : v >= c.lo) && (hi_open ? v < c.hi : v <= c.hi);
}

// The number in `s` when all of it is one (whole for integers, finite for reals).
bool parse_number(const std::string& s, ParamKind kind, bool single_precision, double& out) {
  const char* end = s.data() + s.size();
  if (kind == ParamKind::Integer) {
    int v = 0;
    const auto [ptr, ec] = std::from_chars(s.data(), end, v);
    out = v;
    return ec == std::errc() && ptr == end;
  }
  const auto [ptr, ec] = std::from_chars(s.data(), end, out);
  const bool ok = ec == std::errc() && ptr == end && std::isfinite(out);
  if (single_precision) out = static_cast<float>(out);  // may round to 0 or overflow to infinity
  return ok;
}

}  // namespace

ParamCheck ParamCheck::or_word(std::string w) const {
  ParamCheck c = *this;
  c.words.push_back(std::move(w));
  return c;
}

ParamCheck ParamCheck::or_number(double n) const {
  ParamCheck c = *this;
  c.numbers.push_back(n);
  return c;
}

ParamCheck ParamCheck::as_float() const {
  ParamCheck c = *this;
  c.single_precision = true;
  return c;
}

std::string ParamCheck::describe() const {
  switch (kind) {
    case ParamKind::Text: return "any value";
    case ParamKind::Boolean: return "0 or 1";
    case ParamKind::Choice: return alternatives(words);
    case ParamKind::Integer:
    case ParamKind::Real: break;
  }
  std::vector<std::string> parts = words;
  for (double n : numbers) parts.push_back(number_text(n));
  if (has_range) parts.push_back(range_text(*this));
  return alternatives(parts);
}

bool ParamCheck::accepts(const std::string& value) const {
  switch (kind) {
    case ParamKind::Text: return true;
    case ParamKind::Boolean:
      for (const char* w : {"1", "true", "on", "yes", "0", "false", "off", "no"})
        if (value == w) return true;
      return false;
    case ParamKind::Choice:
    case ParamKind::Integer:
    case ParamKind::Real: break;
  }
  for (const auto& w : words)
    if (value == w) return true;
  if (kind == ParamKind::Choice) return false;
  double v = 0;
  if (!parse_number(value, kind, single_precision, v)) return false;
  for (double n : numbers)
    if (v == n) return true;
  return in_range(*this, v);
}

ParamCheck integer_in(double lo, double hi) {
  ParamCheck c;
  c.kind = ParamKind::Integer;
  c.lo = lo;
  c.hi = hi;
  return c;
}

ParamCheck integer_of(std::vector<double> values) {
  ParamCheck c;
  c.kind = ParamKind::Integer;
  c.has_range = false;
  c.numbers = std::move(values);
  return c;
}

ParamCheck real_in(double lo, double hi, Ends ends) {
  ParamCheck c;
  c.kind = ParamKind::Real;
  c.lo = lo;
  c.hi = hi;
  c.ends = ends;
  return c;
}

ParamCheck boolean_flag() {
  ParamCheck c;
  c.kind = ParamKind::Boolean;
  return c;
}

ParamCheck one_of(std::vector<std::string> choices) {
  ParamCheck c;
  c.kind = ParamKind::Choice;
  c.has_range = false;
  c.words = std::move(choices);
  return c;
}

std::string invalid_param_message(const std::string& owner, const std::string& key, const ParamCheck& check,
                                  const std::string& value) {
  // The one message shape; a value that is no number at all says so
  // ("..., got abc (not an integer)").
  std::string why;
  double v = 0;
  bool is_word = false;
  for (const auto& w : check.words) is_word |= value == w;
  if ((check.kind == ParamKind::Integer || check.kind == ParamKind::Real) && !is_word &&
      !parse_number(value, check.kind, false, v))
    why = check.kind == ParamKind::Integer ? " (not an integer)" : " (not a finite number)";
  return fmt::format("{}: {} must be {}, got {}{}", owner, key, check.describe(), value, why);
}

}  // namespace raylab
