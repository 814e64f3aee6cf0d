#pragma once
// What values a spec parameter accepts, declared beside its name, default and
// help (ParamInfo): Params checks every value, given or default, against it
// when a spec is parsed, with one message shape ("bsp: tplanes must be in
// 0..64, got 65"), so a structure's or scene's factory only reads values and
// `raylab accels --json` can list each parameter's valid values.
#include <limits>
#include <string>
#include <vector>

namespace raylab {

enum class ParamKind {
  Text,     // anything (the factory parses it, e.g. a resolution AxBxC)
  Integer,  // a whole number in the range, or one of `numbers`, or one of `words`
  Real,     // a finite number in the range, or one of `words`
  Boolean,  // 0/1, true/false, on/off, yes/no
  Choice,   // one of `words`
};

inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// Which ends of a real range belong to it: [lo, hi], (lo, hi], [lo, hi), (lo, hi).
enum class Ends { Closed, OpenLow, OpenHigh, Open };

struct ParamCheck {
  ParamKind kind = ParamKind::Text;
  double lo = -kUnbounded, hi = kUnbounded;  // the numeric range (infinite: no bound on that side)
  Ends ends = Ends::Closed;
  bool has_range = true;              // false: only `numbers` and `words` (e.g. "3, 7 or 13")
  std::vector<double> numbers;        // numbers accepted besides the range ("0 or in 2..64")
  std::vector<std::string> words;     // Choice: the values; Integer/Real: words accepted as well ("auto")
  bool single_precision = false;      // Real: the range is checked on the value rounded to float

  // Also accept the word `w` (e.g. "auto") or the number `n` outside the range.
  ParamCheck or_word(std::string w) const;
  ParamCheck or_number(double n) const;
  // Real: check the range on the value rounded to float (the factory stores
  // a float): a finite number may round to 0 or overflow to infinity, which
  // an unbounded range includes unless it is open at the top (Ends::Open).
  ParamCheck as_float() const;

  // The valid values in words: "in 0..64", "in (0, 64]", ">= 1", "3, 7 or 13",
  // "auto or in 0..64", "binned, sweep or sbvh", "0 or 1".
  std::string describe() const;
  // Whether `value` is valid.
  bool accepts(const std::string& value) const;
};

// Whole numbers lo..hi (hi = kUnbounded: ">= lo").
ParamCheck integer_in(double lo, double hi);
// Exactly these whole numbers ("4, 8 or 16").
ParamCheck integer_of(std::vector<double> values);
// Finite numbers between lo and hi, ends as given (hi = kUnbounded: ">= lo" / "> lo").
ParamCheck real_in(double lo, double hi, Ends ends = Ends::Closed);
ParamCheck boolean_flag();
ParamCheck one_of(std::vector<std::string> choices);

// The one message for a value outside its declaration.
std::string invalid_param_message(const std::string& owner, const std::string& key, const ParamCheck& check,
                                  const std::string& value);

}  // namespace raylab
