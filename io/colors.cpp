// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "colors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace point_detail {

namespace {

Color lerp(const Color& a, const Color& b, double t)
{
  Color c;
  for(int i = 0; i < 3; ++i) c[std::size_t(i)] = (unsigned char)std::lround(a[std::size_t(i)] + (b[std::size_t(i)] - a[std::size_t(i)]) * t);
  return c;
}

/// Piecewise-linear colour map over evenly spaced control colours, t in [0, 1].
template <std::size_t N>
Color sample(const Color (&stops)[N], double t)
{
  t = std::clamp(t, 0.0, 1.0) * double(N - 1);
  const std::size_t i = std::min<std::size_t>(std::size_t(t), N - 2);
  return lerp(stops[i], stops[i + 1], t - double(i));
}

// Moreland's cool-warm diverging map and a viridis-like sequential map, a few stops each.
const Color cool_warm[] = {{59, 76, 192}, {124, 159, 249}, {192, 212, 245}, {242, 240, 238}, {242, 203, 183}, {238, 133, 105}, {180, 4, 38}};
const Color viridis[] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};

} // namespace

double percentile(std::vector<double> v, double q)
{
  if(v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

Color scale_color(Coloring::Scale scale, double t)
{
  return scale == Coloring::Scale::diverging ? sample(cool_warm, t) : sample(viridis, t);
}

namespace {
bool negligible(double v, double largest) { return std::abs(v) <= 1e-12 * largest; }
} // namespace

Coloring diverging_colors(const std::vector<double>& values)
{
  double largest = 0;
  for(double v : values) largest = std::max(largest, std::abs(v));
  std::vector<double> magnitude;
  for(double v : values)
    if(!negligible(v, largest)) magnitude.push_back(std::abs(v));
  if(2 * magnitude.size() > values.size()) {
    magnitude.resize(values.size());
    std::transform(values.begin(), values.end(), magnitude.begin(), [](double v) { return std::abs(v); });
  }
  const double r = percentile(std::move(magnitude), 0.98);
  return diverging_colors(values, r > 0 ? r : 1.0);
}

Coloring diverging_colors(const std::vector<double>& values, double limit)
{
  Coloring out;
  out.scale = Coloring::Scale::diverging;
  out.lo = -limit;
  out.hi = limit;
  out.colors.reserve(values.size());
  for(double v : values) out.colors.push_back(sample(cool_warm, 0.5 + 0.5 * v / limit));
  return out;
}

Coloring sequential_colors(const std::vector<double>& values)
{
  double lo = percentile(values, 0.02), hi = percentile(values, 0.98);
  if(!(hi > lo) && !values.empty()) {
    // Most points share one value: span it and the values that differ from it.
    const double common = lo;
    double largest = 0;
    for(double v : values) largest = std::max(largest, std::abs(v - common));
    std::vector<double> others;
    for(double v : values)
      if(!negligible(v - common, largest)) others.push_back(v);
    if(!others.empty()) {
      lo = std::min(common, percentile(others, 0.02));
      hi = std::max(common, percentile(others, 0.98));
    }
  }
  Coloring out;
  out.scale = Coloring::Scale::sequential;
  out.lo = lo;
  out.hi = hi;
  out.colors.reserve(values.size());
  for(double v : values) out.colors.push_back(sample(viridis, hi > lo ? (v - lo) / (hi - lo) : 0.5));
  return out;
}

void emphasize(Coloring& coloring, const std::vector<double>& flags, const std::string& flagged)
{
  coloring.flagged = flagged;
  coloring.colors.resize(flags.size(), Color{200, 200, 200});
  coloring.emphasized.assign(flags.size(), 0);
  coloring.emphasized_count = 0;
  for(std::size_t i = 0; i < flags.size(); ++i)
    if(flags[i] == 1) {
      coloring.colors[i] = flag_color;
      coloring.emphasized[i] = 1;
      ++coloring.emphasized_count;
    }
}

Coloring flag_colors(const std::vector<double>& flags)
{
  Coloring out;
  out.scale = Coloring::Scale::flag;
  emphasize(out, flags, "");
  return out;
}

Coloring colors_for(const std::vector<double>& values)
{
  bool flags = true, negative = false, positive = false;
  for(double v : values) {
    flags = flags && (v == 0 || v == 1);
    negative = negative || v < 0;
    positive = positive || v > 0;
  }
  if(flags) return flag_colors(values);
  return negative && positive ? diverging_colors(values) : sequential_colors(values);
}

Coloring label_colors(const std::vector<std::size_t>& labels)
{
  Coloring coloring;
  std::vector<Color>& out = coloring.colors;
  out.reserve(labels.size());
  for(std::size_t label : labels) {
    // A hash spreads neighbouring labels over the hue circle; saturation and value vary a little too.
    std::uint64_t h = std::uint64_t(label) * 0x9E3779B97F4A7C15ull;
    h ^= h >> 29;
    const double hue = double(h % 3600) / 600.0, sat = 0.55 + 0.4 * double((h >> 12) % 100) / 100.0,
                 val = 0.7 + 0.3 * double((h >> 24) % 100) / 100.0;
    const int sector = int(hue);
    const double f = hue - sector, p = val * (1 - sat), q = val * (1 - sat * f), t = val * (1 - sat * (1 - f));
    const double rgb[6][3] = {{val, t, p}, {q, val, p}, {p, val, t}, {p, q, val}, {t, p, val}, {val, p, q}};
    const double* c = rgb[sector % 6];
    out.push_back({static_cast<unsigned char>(255 * c[0]), static_cast<unsigned char>(255 * c[1]),
                   static_cast<unsigned char>(255 * c[2])});
  }
  return coloring;
}

std::string quantity_of(const std::string& property)
{
  // Coordinates carry no unit of their own: lengths are in the model's units.
  static const std::pair<const char*, const char*> names[] = {
    {"detail_normal", "detail along the normal, model units"},
    {"detail_magnitude", "signed detail magnitude, model units"},
    {"detail_x", "detail x, model units"},
    {"detail_y", "detail y, model units"},
    {"detail_z", "detail z, model units"},
    {"displacement", "displacement, model units"},
    {"mean_curvature", "mean curvature, 1 / model unit"},
    {"inserted", "new points"},
    {"in_roi", "region of interest"},
  };
  for(const auto& [name, quantity] : names)
    if(property == name) return quantity;
  return property;
}

} // namespace point_detail
