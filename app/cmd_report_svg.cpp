#include "app/cmd_report_svg.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace raylab::cli {

std::string html_escape(const std::string& text) {
  std::string s;
  s.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': s += "&amp;"; break;
      case '<': s += "&lt;"; break;
      case '>': s += "&gt;"; break;
      case '"': s += "&quot;"; break;
      default: s += c;
    }
  }
  return s;
}

std::string short_number(double v) {
  if (!std::isfinite(v)) return "n/a";
  const double a = std::fabs(v);
  if (a == 0.0) return "0";
  if (a >= 1e6 || a < 1e-3) return fmt::format("{:.2g}", v);
  if (a >= 100) return fmt::format("{:.0f}", v);
  if (a >= 10) return fmt::format("{:.1f}", v);
  if (a >= 1) return fmt::format("{:.2f}", v);
  return fmt::format("{:.3f}", v);
}

namespace {

// About six round linear steps over [0, hi].
std::vector<double> ticks_for(double hi) {
  std::vector<double> t;
  const double raw = hi / 6.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  for (double v = 0; v <= hi * (1 + 1e-9); v += step) t.push_back(v);
  return t;
}

}  // namespace

std::string svg_bar_chart(const BarChart& c) {
  const int label_w = 190, note_w = 170, plot_w = 420, row_h = 20, bottom = 44;
  const int top = c.subtitle.empty() ? 34 : 52;
  const int width = label_w + plot_w + note_w;
  const int height = top + static_cast<int>(c.rows.size()) * row_h + bottom;
  // The axis runs from 0 to past the largest value, whisker and the reference.
  double hi = 0;
  auto take = [&](double v) {
    if (std::isfinite(v)) hi = std::max(hi, v);
  };
  for (const auto& r : c.rows) {
    take(r.value);
    take(r.hi);
  }
  take(c.reference);
  hi = hi > 0 ? hi * 1.05 : 1.0;
  auto x_of = [&](double v) { return label_w + std::clamp(v / hi, 0.0, 1.0) * plot_w; };
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"{}\" class=\"chart\" width=\"{}\" height=\"{}\" "
      "viewBox=\"0 0 {} {}\" font-family=\"sans-serif\" font-size=\"11\" role=\"img\" aria-label=\"{}\">\n",
      html_escape(c.id), width, height, width, height, html_escape(c.title));
  s += fmt::format("<rect width=\"{}\" height=\"{}\" fill=\"white\"/>\n", width, height);
  s += fmt::format("<text x=\"4\" y=\"16\" font-size=\"13\" font-weight=\"bold\">{}</text>\n", html_escape(c.title));
  if (!c.subtitle.empty())
    s += fmt::format("<text x=\"4\" y=\"31\" fill=\"#555\">{}</text>\n", html_escape(c.subtitle));
  const int plot_bottom = top + static_cast<int>(c.rows.size()) * row_h;
  for (double t : ticks_for(hi)) {
    const double x = x_of(t);
    s += fmt::format("<line x1=\"{:.1f}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{}\" stroke=\"#e0e0e0\"/>\n", x, top - 4, x, plot_bottom);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\" fill=\"#444\">{}</text>\n", x, plot_bottom + 14,
                     short_number(t));
  }
  s += fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#444\"/>\n", label_w, top - 4, label_w,
                   plot_bottom);
  s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#222\">{}</text>\n", label_w + plot_w / 2,
                   plot_bottom + 32, html_escape(c.x_label));
  for (size_t i = 0; i < c.rows.size(); ++i) {
    const BarRow& r = c.rows[i];
    const int y = top + static_cast<int>(i) * row_h;
    s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>\n", label_w - 6, y + 14, html_escape(r.label));
    if (std::isfinite(r.value) && r.value >= 0) {
      const double x0 = x_of(0.0), x1 = x_of(r.value);
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{}\" width=\"{:.1f}\" height=\"{}\" fill=\"{}\"><title>{}: {}</title></rect>\n",
                       x0, y + 3, std::max(1.0, x1 - x0), row_h - 6, r.colour, html_escape(r.label),
                       short_number(r.value));
      if (std::isfinite(r.lo) && std::isfinite(r.hi)) {
        const double a = x_of(r.lo), b = x_of(r.hi), ym = y + row_h / 2.0;
        s += fmt::format("<path d=\"M{:.1f} {:.1f}H{:.1f}M{:.1f} {:.1f}V{:.1f}M{:.1f} {:.1f}V{:.1f}\" stroke=\"#000\" "
                         "stroke-width=\"1.2\" fill=\"none\"/>\n",
                         a, ym, b, a, ym - 4, ym + 4, b, ym - 4, ym + 4);
      }
    } else {
      s += fmt::format("<text x=\"{}\" y=\"{}\" fill=\"#888\">n/a</text>\n", label_w + 4, y + 14);
    }
    s += fmt::format("<text x=\"{}\" y=\"{}\" fill=\"#222\">{}</text>\n", label_w + plot_w + 6, y + 14, html_escape(r.note));
  }
  if (std::isfinite(c.reference)) {
    const double x = x_of(c.reference);
    s += fmt::format("<line x1=\"{:.1f}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{}\" stroke=\"#c00\" stroke-dasharray=\"4 3\"/>\n", x,
                     top - 6, x, plot_bottom);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{}\" fill=\"#c00\" text-anchor=\"middle\">{}</text>\n", x, top - 8,
                     html_escape(c.reference_label));
  }
  s += "</svg>\n";
  return s;
}

}  // namespace raylab::cli
