#pragma once
// Spec strings: "name" or "name:key=value,key=value". The same syntax names
// accelerators ("bvh:leaf=4,bins=16") and procedural scenes ("soup:n=1000").
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/param_check.h"

namespace raylab {

class SpecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Spec {
  std::string name;
  std::map<std::string, std::string> params;  // ordered, so to_string is canonical

  static Spec parse(const std::string& text);  // throws SpecError on malformed text
  std::string to_string() const;
};

// Splits a list such as "bvh:leaf=4,bins=16,brute,embree:robust=1" into specs:
// a comma-separated token that contains '=' but no ':' continues the previous
// spec's parameters. ';' always separates specs.
std::vector<std::string> split_spec_list(const std::string& text);

// The pieces of `text` between separators, empty ones included ("a,,b" ->
// "a", "", "b"; "" -> one empty piece).
std::vector<std::string> split_at(const std::string& text, char sep);

// Declared parameter of a spec: name, default value, a one-line help and the
// values it accepts (checked by Params, so factories only read).
struct ParamInfo {
  std::string name;
  std::string default_value;
  std::string help;
  ParamCheck check{};
};

// Typed access to a spec's parameters after they were checked against the
// declared list: undeclared keys and values outside their declaration
// (ParamInfo::check) are rejected on construction.
class Params {
 public:
  Params(std::string owner, const std::vector<ParamInfo>& declared,
         const std::map<std::string, std::string>& given);

  const std::string& str(const std::string& key) const;
  int integer(const std::string& key) const;
  double real(const std::string& key) const;
  bool boolean(const std::string& key) const;

  bool given(const std::string& key) const { return given_.count(key) != 0; }

 private:
  std::string owner_;
  std::map<std::string, std::string> values_;
  std::map<std::string, std::string> given_;
};

}  // namespace raylab
