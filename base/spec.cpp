#include "base/spec.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

namespace raylab {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

}  // namespace

Spec Spec::parse(const std::string& text) {
  Spec spec;
  const auto colon = text.find(':');
  spec.name = trim(text.substr(0, colon));
  if (spec.name.empty()) throw SpecError(fmt::format("empty name in spec '{}'", text));
  if (colon == std::string::npos) return spec;
  const std::string rest = text.substr(colon + 1);
  if (trim(rest).empty()) return spec;
  for (const auto& item : split_at(rest, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw SpecError(fmt::format("parameter '{}' in spec '{}' is not of the form key=value", trim(item), text));
    const std::string key = trim(item.substr(0, eq));
    const std::string value = trim(item.substr(eq + 1));
    if (key.empty() || value.empty())
      throw SpecError(fmt::format("parameter '{}' in spec '{}' needs a key and a value", trim(item), text));
    if (spec.params.count(key)) throw SpecError(fmt::format("parameter '{}' given twice in spec '{}'", key, text));
    spec.params[key] = value;
  }
  return spec;
}

std::string Spec::to_string() const {
  std::string s = name;
  char sep = ':';
  for (const auto& [k, v] : params) {
    s += sep;
    s += k + "=" + v;
    sep = ',';
  }
  return s;
}

std::vector<std::string> split_spec_list(const std::string& text) {
  std::vector<std::string> out;
  for (const auto& group : split_at(text, ';')) {
    for (const auto& raw : split_at(group, ',')) {
      const std::string tok = trim(raw);
      if (tok.empty()) continue;
      const bool continues = tok.find('=') != std::string::npos && tok.find(':') == std::string::npos;
      if (continues && !out.empty() && out.back().find(':') != std::string::npos) {
        out.back() += "," + tok;
      } else {
        out.push_back(tok);
      }
    }
  }
  return out;
}

Params::Params(std::string owner, const std::vector<ParamInfo>& declared,
               const std::map<std::string, std::string>& given)
    : owner_(std::move(owner)), given_(given) {
  for (const auto& p : declared) values_[p.name] = p.default_value;
  for (const auto& [k, v] : given) {
    if (!values_.count(k)) {
      std::string known;
      for (const auto& p : declared) known += (known.empty() ? "" : ", ") + p.name;
      throw SpecError(fmt::format("unknown parameter '{}' for '{}' (parameters: {})", k, owner_,
                                  known.empty() ? "none" : known));
    }
    values_[k] = v;
  }
  for (const auto& p : declared) {
    const std::string& v = values_[p.name];
    if (!p.check.accepts(v)) throw SpecError(invalid_param_message(owner_, p.name, p.check, v));
  }
}

const std::string& Params::str(const std::string& key) const {
  const auto it = values_.find(key);
  if (it == values_.end()) throw SpecError(fmt::format("'{}' has no parameter '{}'", owner_, key));
  return it->second;
}

int Params::integer(const std::string& key) const {
  const std::string& s = str(key);
  int v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size())
    throw SpecError(fmt::format("parameter {}={} of '{}' is not an integer", key, s, owner_));
  return v;
}

double Params::real(const std::string& key) const {
  const std::string& s = str(key);
  double v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v))
    throw SpecError(fmt::format("parameter {}={} of '{}' is not a finite number", key, s, owner_));
  return v;
}

bool Params::boolean(const std::string& key) const {
  const std::string& s = str(key);
  if (s == "1" || s == "true" || s == "on" || s == "yes") return true;
  if (s == "0" || s == "false" || s == "off" || s == "no") return false;
  throw SpecError(fmt::format("parameter {}={} of '{}' is not a boolean (use 0 or 1)", key, s, owner_));
}

std::vector<std::string> split_at(const std::string& text, char sep) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const auto pos = text.find(sep, start);
    out.push_back(text.substr(start, pos == std::string::npos ? std::string::npos : pos - start));
    if (pos == std::string::npos) return out;
    start = pos + 1;
  }
}

}  // namespace raylab
