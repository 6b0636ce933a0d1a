// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "render.h"

#include "files.h"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>
#include <tuple>

namespace point_detail {

View parse_view(const std::string& text)
{
  if(text == "front") return {0, 0};
  if(text == "back") return {180, 0};
  if(text == "left") return {-90, 0};
  if(text == "right") return {90, 0};
  if(text == "top") return {0, 89.9};
  if(text == "bottom") return {0, -89.9};
  if(text == "iso") return {35, 25};
  std::istringstream in(text);
  View v;
  char comma = 0;
  if(in >> v.azimuth >> comma >> v.elevation && comma == ',' && in.peek() == EOF && std::isfinite(v.azimuth) &&
     std::abs(v.elevation) <= 90)
    return v;
  throw Cli_error("bad view '" + text + "': use front, back, left, right, top, bottom, iso or AZIMUTH,ELEVATION in degrees");
}

namespace {
/// Distance of every sample to its 4th nearest other sample: a splat of that radius closes the gaps of
/// sparse regions without bloating dense ones.
std::vector<double> local_spacing(const std::vector<Point>& points)
{
  using SC = CGAL::Simple_cartesian<double>;
  using Search = CGAL::Orthogonal_k_neighbor_search<CGAL::Search_traits_3<SC>>;
  std::vector<SC::Point_3> pts;
  pts.reserve(points.size());
  for(const Point& p : points) pts.emplace_back(p.x(), p.y(), p.z());
  Search::Tree tree(pts.begin(), pts.end());
  std::vector<double> d(pts.size(), 0.0);
  for(std::size_t i = 0; i < pts.size(); ++i) {
    Search search(tree, pts[i], unsigned(std::min<std::size_t>(5, pts.size())));
    for(auto it = search.begin(); it != search.end(); ++it) d[i] = std::sqrt(it->second); // sorted: the last is the farthest
  }
  return d;
}
} // namespace

namespace {

/// 3x5 glyphs of the characters numbers and the legend's names need (letters drawn in capitals), one row per
/// 3 bits (top row first).
int glyph(char c)
{
  switch(c) {
  case '0': return 0b111101101101111;
  case '1': return 0b010110010010111;
  case '2': return 0b111001111100111;
  case '3': return 0b111001111001111;
  case '4': return 0b101101111001001;
  case '5': return 0b111100111001111;
  case '6': return 0b111100111101111;
  case '7': return 0b111001001001001;
  case '8': return 0b111101111101111;
  case '9': return 0b111101111001111;
  case '.': return 0b000000000000010;
  case ',': return 0b000000000010100;
  case '-': return 0b000000111000000;
  case '+': return 0b000010111010000;
  case 'e': return 0b010101111100011; // the exponent of a number
  case '/': return 0b001001010100100;
  case '(': return 0b001010010010001;
  case ')': return 0b100010010010100;
  case '_': return 0b000000000000111;
  case 'A': return 0b010101111101101;
  case 'B': return 0b110101110101110;
  case 'C': return 0b011100100100011;
  case 'D': return 0b110101101101110;
  case 'E': return 0b111100110100111;
  case 'F': return 0b111100110100100;
  case 'G': return 0b011100101101011;
  case 'H': return 0b101101111101101;
  case 'I': return 0b111010010010111;
  case 'J': return 0b001001001101010;
  case 'K': return 0b101101110101101;
  case 'L': return 0b100100100100111;
  case 'M': return 0b101111111101101;
  case 'N': return 0b110101101101101;
  case 'O': return 0b010101101101010;
  case 'P': return 0b110101110100100;
  case 'Q': return 0b010101101111011;
  case 'R': return 0b110101110101101;
  case 'S': return 0b011100010001110;
  case 'T': return 0b111010010010010;
  case 'U': return 0b101101101101111;
  case 'V': return 0b101101101101010;
  case 'W': return 0b101101111111101;
  case 'X': return 0b101101010101101;
  case 'Y': return 0b101101010010010;
  case 'Z': return 0b111001010100111;
  default: return 0;
  }
}

} // namespace

bool legend_can_write(char c) { return c == ' ' || glyph(char(std::toupper(static_cast<unsigned char>(c)))) != 0; }

namespace {

/// A legend name in the glyphs' capitals.
std::string capitals(std::string text)
{
  for(char& c : text) c = char(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

/// An RGB picture to draw the legend on.
struct Canvas
{
  std::vector<unsigned char>& rgb;
  int width, height;

  void fill(int x0, int y0, int w, int h, const Color& c)
  {
    for(int y = std::max(0, y0); y < std::min(height, y0 + h); ++y)
      for(int x = std::max(0, x0); x < std::min(width, x0 + w); ++x)
        for(int k = 0; k < 3; ++k) rgb[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3 + std::size_t(k)] = c[std::size_t(k)];
  }
  /// Text in 3x5 glyphs scaled by `size`; returns its width. `anchor` 0 left, 0.5 centred, 1 right of x.
  int text(const std::string& t, int x, int y, int size, double anchor = 0)
  {
    const int advance = 4 * size, w = int(t.size()) * advance - size;
    x -= int(anchor * w);
    for(char c : t) {
      const int bits = glyph(c);
      for(int row = 0; row < 5; ++row)
        for(int col = 0; col < 3; ++col)
          if(bits >> (14 - 3 * row - col) & 1) fill(x + col * size, y + row * size, size, size, Color{40, 40, 40});
      x += advance;
    }
    return w;
  }
};

std::string number(double v)
{
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

/// Height of the legend's bar (a line of text and a margin), and of its name with the gap below it.
int legend_bar_height(int width) { return 5 * std::max(1, width / 400) + 2; }
int legend_name_height(int width) { return legend_bar_height(width) + 2 * std::max(1, width / 400); }

/// The legend strip: the quantity's name over the colour bar with its ends (and 0 for a diverging map), and a
/// swatch of the flag colour with the count of flagged points (beside the bar, or alone).
void draw_legend(Canvas canvas, int top, const Coloring& coloring)
{
  const int size = std::max(1, canvas.width / 400), bar_height = legend_bar_height(canvas.width);
  const int named = coloring.quantity.empty() ? 0 : legend_name_height(canvas.width);
  const int y = top + named + (canvas.height - top - named - bar_height) / 2;
  if(named) canvas.text(capitals(coloring.quantity), canvas.width / 2, y - named, size, 0.5);
  const bool bar = coloring.scale == Coloring::Scale::diverging || coloring.scale == Coloring::Scale::sequential;
  if(bar) {
    const int length = canvas.width / 2, x0 = (canvas.width - length) / 2;
    for(int x = 0; x < length; ++x) {
      const double t = (x + 0.5) / length;
      canvas.fill(x0 + x, y, 1, bar_height, scale_color(coloring.scale, t));
    }
    canvas.text(number(coloring.lo), x0 - 3 * size, y + 1, size, 1);
    canvas.text(number(coloring.hi), x0 + length + 3 * size, y + 1, size, 0);
    if(coloring.scale == Coloring::Scale::diverging) canvas.fill(x0 + length / 2, y - size, 1, bar_height + 2 * size, Color{40, 40, 40});
  }
  if(coloring.emphasized_count > 0) {
    const int x0 = (bar ? canvas.width * 7 / 8 : canvas.width / 2) - 6 * size;
    canvas.fill(x0, y, bar_height, bar_height, flag_color);
    const std::string count = "+" + std::to_string(coloring.emphasized_count);
    canvas.text(bar && !coloring.flagged.empty() ? count + " " + capitals(coloring.flagged) : count,
                x0 + bar_height + 3 * size, y + 1, size, 0);
  }
}

} // namespace

std::string render_png(const std::vector<Point>& points, const std::vector<Vector>& normals, const Coloring& coloring,
                       const Render_settings& settings)
{
  if(points.empty()) throw Cli_error("nothing to render: no points");
  const std::vector<Color>& colors = coloring.colors;
  constexpr int ss = 2; // supersampling factor
  const bool legend = (coloring.scale != Coloring::Scale::none || coloring.emphasized_count > 0) && settings.height >= 80;
  const int legend_height =
    legend ? std::max(20, settings.height / 25) + (coloring.quantity.empty() ? 0 : legend_name_height(settings.width)) : 0;
  const int W = settings.width * ss, H = (settings.height - legend_height) * ss; // the model's part of the picture
  const double pi = CGAL_PI;
  const double az = settings.view.azimuth * pi / 180, el = settings.view.elevation * pi / 180;
  const Eigen::Vector3d to_camera(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  const Eigen::Vector3d right = Eigen::Vector3d::UnitY().cross(to_camera).normalized();
  const Eigen::Vector3d up = to_camera.cross(right);
  const Eigen::Vector3d light = (to_camera + 0.35 * right + 0.45 * up).normalized();

  const std::size_t n = points.size();
  std::vector<Eigen::Vector3d> view(n); // (u, v, depth towards the camera)
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for(std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(points[i].x(), points[i].y(), points[i].z());
    view[i] = Eigen::Vector3d(p.dot(right), p.dot(up), p.dot(to_camera));
    lo = lo.cwiseMin(view[i]);
    hi = hi.cwiseMax(view[i]);
  }
  const double extent_u = std::max(hi.x() - lo.x(), 1e-300), extent_v = std::max(hi.y() - lo.y(), 1e-300);
  const double scale = 0.9 * std::min(W / extent_u, H / extent_v);
  const std::vector<double> spacings = local_spacing(points);
  const double spacing = percentile(spacings, 0.5);

  std::vector<float> depth(std::size_t(W) * std::size_t(H), -std::numeric_limits<float>::infinity());
  std::vector<Color> image(depth.size(), Color{255, 255, 255});
  // Splats of equal depth keep the first drawn: drawn in the order of their positions, the picture is the same
  // whatever the order of the points (doc/design.md, "One neighbourhood rule").
  std::vector<std::size_t> draw_order(n);
  std::iota(draw_order.begin(), draw_order.end(), std::size_t(0));
  std::sort(draw_order.begin(), draw_order.end(), [&](std::size_t a, std::size_t b) {
    return std::make_tuple(points[a].x(), points[a].y(), points[a].z(), a) <
           std::make_tuple(points[b].x(), points[b].y(), points[b].z(), b);
  });
  for(const std::size_t i : draw_order) {
    // Flagged points are drawn over the others (a few spacings nearer the camera) and never thinner than 2 pixels.
    const bool emphasized = !coloring.emphasized.empty() && coloring.emphasized[i];
    const double radius = std::clamp(0.75 * settings.splat_scale * spacings[i] * scale, (emphasized ? 2.0 : 1.0) * ss, 20.0 * ss);
    const int r = int(std::ceil(radius));
    const double x = W / 2.0 + (view[i].x() - 0.5 * (lo.x() + hi.x())) * scale;
    const double y = H / 2.0 - (view[i].y() - 0.5 * (lo.y() + hi.y())) * scale;
    double shade = 0.85;
    if(!normals.empty()) {
      const Eigen::Vector3d nv(normals[i].x(), normals[i].y(), normals[i].z());
      shade = 0.25 + 0.75 * std::abs(nv.normalized().dot(light)); // two-sided: unoriented normals shade too
    }
    const Color base = colors.empty() ? Color{200, 200, 200} : colors[i];
    Color c;
    for(int k = 0; k < 3; ++k) c[std::size_t(k)] = (unsigned char)std::lround(std::min(255.0, base[std::size_t(k)] * shade));
    const float z = float(view[i].z() + (emphasized ? 3 * spacings[i] : 0.0));
    const int cx = int(std::lround(x)), cy = int(std::lround(y));
    for(int dy = -r; dy <= r; ++dy)
      for(int dx = -r; dx <= r; ++dx) {
        const int px = cx + dx, py = cy + dy;
        if(px < 0 || py < 0 || px >= W || py >= H || (px - x) * (px - x) + (py - y) * (py - y) > radius * radius) continue;
        const std::size_t at = std::size_t(py) * std::size_t(W) + std::size_t(px);
        if(z > depth[at]) { depth[at] = z; image[at] = c; }
      }
  }
  // Outline where depth jumps by more than a few spacings: separates overlapping parts.
  const float jump = float(4 * std::max(spacing, 1e-12));
  std::vector<Color> outlined = image;
  for(int y = 1; y + 1 < H; ++y)
    for(int x = 1; x + 1 < W; ++x) {
      const std::size_t at = std::size_t(y) * std::size_t(W) + std::size_t(x);
      if(!std::isfinite(depth[at])) continue;
      // A background pixel counts as silhouette only when the background extends beyond it (not a gap).
      auto background = [&](std::size_t p) {
        return !std::isfinite(depth[p]) && (p < 2 * std::size_t(W) || p + 2 * std::size_t(W) >= depth.size() ||
                                            !std::isfinite(depth[p + (p - at)]));
      };
      for(std::size_t nb : {at - 1, at + 1, at - std::size_t(W), at + std::size_t(W)})
        if(background(nb) || depth[nb] - depth[at] > jump) {
          for(auto& ch : outlined[at]) ch = (unsigned char)(ch * 0.45);
          break;
        }
    }
  // Box-filter the supersampled image down.
  std::vector<unsigned char> rgb(std::size_t(settings.width) * std::size_t(settings.height) * 3, 255);
  for(int y = 0; y < settings.height - legend_height; ++y)
    for(int x = 0; x < settings.width; ++x)
      for(int k = 0; k < 3; ++k) {
        int sum = 0;
        for(int sy = 0; sy < ss; ++sy)
          for(int sx = 0; sx < ss; ++sx)
            sum += outlined[std::size_t(y * ss + sy) * std::size_t(W) + std::size_t(x * ss + sx)][std::size_t(k)];
        rgb[(std::size_t(y) * std::size_t(settings.width) + std::size_t(x)) * 3 + std::size_t(k)] = (unsigned char)(sum / (ss * ss));
      }
  if(legend) draw_legend(Canvas{rgb, settings.width, settings.height}, settings.height - legend_height, coloring);
  std::string png;
  stbi_write_png_to_func([](void* context, void* data, int size) { static_cast<std::string*>(context)->append(static_cast<char*>(data), std::size_t(size)); },
                         &png, settings.width, settings.height, 3, rgb.data(), settings.width * 3);
  if(png.empty()) throw Cli_error("PNG encoding failed");
  return png;
}

} // namespace point_detail
