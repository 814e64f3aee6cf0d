#pragma once
// Inline SVG charts for `raylab report`: horizontal bar charts with min-max
// whiskers, written as self-contained <svg> text (no scripts, no external
// fonts), so the page needs no network. Bars start at zero on a linear axis,
// so a bar's length is its value (a log axis has no zero to grow from).
#include <limits>
#include <string>
#include <vector>

namespace raylab::cli {

struct BarRow {
  std::string label;
  std::string colour;  // "#rrggbb"
  double value = 0.0;  // the bar (e.g. median); NaN: drawn as "n/a"
  double lo = std::numeric_limits<double>::quiet_NaN();  // whisker range, NaN: none
  double hi = std::numeric_limits<double>::quiet_NaN();
  std::string note;  // printed right of the bar (e.g. "0.41x, 3 of 3 scenes")
};

struct BarChart {
  std::string id;  // the element id (tests and links find charts by it)
  std::string title;
  std::string subtitle;  // a second line under the title (empty = none)
  std::string x_label;
  // A vertical reference line (e.g. 1 = as fast as Embree), drawn over the bars.
  double reference = std::numeric_limits<double>::quiet_NaN();
  std::string reference_label;
  std::vector<BarRow> rows;
};

std::string svg_bar_chart(const BarChart& chart);

// Escapes &, <, >, " for HTML and SVG text.
std::string html_escape(const std::string& text);

// "0.05", "1.2", "350", "1.2e+06": short tick and table numbers.
std::string short_number(double v);

}  // namespace raylab::cli
