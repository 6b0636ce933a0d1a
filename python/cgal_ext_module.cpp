// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The compiled part of the Python package `cgal_ext` (`cgal_ext._core`, doc/python.md): the library's algorithms
// and the program's readers, writers and pictures on numpy arrays. float64 (n, 3) arrays are read in place through
// property maps over the caller's memory (C- or F-ordered, any strides); other numbers and nested lists are
// converted once. Results are new arrays, named tuples where there are several. The GIL is released while the
// library computes; a `progress` callable is called from the calling thread with the GIL taken back, and an
// exception it raises (or Ctrl-C) cancels the computation and is raised.
// The module is registered by concern: the library's functions, the program's I/O, the threads, the editing class.
#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_neighbor_graph.h>
#include <CGAL_ext/compute_simplification_sample_points.h>
#include <CGAL_ext/detect_sparse_directions.h>
#include <CGAL_ext/diffuse_points.h>
#include <CGAL_ext/enhance_geometric_details.h>
#include <CGAL_ext/estimate_mean_curvature.h>
#include <CGAL_ext/estimate_oriented_normals.h>
#include <CGAL_ext/refit_normals.h>
#include <CGAL_ext/scale_geometric_details.h>
#include <CGAL_ext/upsample_point_set.h>

#include "colors.h"
#include "edit_spec.h"
#include "point_io.h"
#include "program_basics.h"
#include "render.h"

#include <CGAL/Simple_cartesian.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <boost/property_map/function_property_map.hpp>
#include <boost/range/counting_range.hpp>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace py = pybind11;
using namespace pybind11::literals;

// The module's parts, in order: each uses the ones before it.
// clang-format off
#include "core/arrays.h"
#include "core/progress.h"
#include "core/settings.h"
#include "core/functions.h"
#include "core/deformation_settings.h"
#include "core/editing.h"
// clang-format on

namespace {

// ---- docstrings -------------------------------------------------------------------------------------------------

const char* const points_doc = R"(points : (n, 3) array_like
    The points. float64 arrays are read in place (any memory layout); float32, integers and nested lists are
    converted to float64 once, a copy.)";
const char* const normals_doc = R"(normals : (n, 3) array_like, optional
    Unit normals, read as points are. None estimates them (jet fitting and a consistent orientation).)";
const char* const progress_doc = R"(progress : callable, optional
    Called as progress(fraction), fraction in [0, 1], from the calling thread. An exception raised in it
    cancels the computation, which then raises it; Ctrl-C does the same with KeyboardInterrupt.)";
const char* const filter_doc = R"(k : int
    Neighbours of the point-set Laplacian (each point's k nearest, itself not counted; fewer than the points).
order : {"linear", "quadric", "cubic"}
    The transfer function f(K) of the details (Miao et al. 2007, Sect. 3).
lam, mu : float
    Its pass-band and highest frequencies, 0 < lam < mu (mu unused by "linear").
weights : {"uniform", "distance"}
    The Laplacian's weights: uniform, or inverse distance.)";
const char* const raises_doc = R"(Raises
------
ValueError
    A bad argument (shape, dtype, index, setting) or input the library refuses, with its message.
RuntimeError
    A numerical failure (a factorisation that fails), with the library's message.)";

std::string doc(const std::string& summary, const std::vector<std::string>& parameters, const std::string& returns,
                bool raises = true)
{
  std::string text = summary + "\n\nParameters\n----------\n";
  for(const std::string& p : parameters) text += p + "\n";
  if(!returns.empty()) text += "\nReturns\n-------\n" + returns + "\n";
  if(raises) text += std::string("\n") + raises_doc + "\n";
  return text;
}

// STREAM's triad on TBB's threads, as the diffusion's loops run: (median, best) GB/s over `repetitions` passes.
py::tuple triad_bandwidth(std::size_t elements, int repetitions)
{
  if(elements == 0 || repetitions < 1)
    throw std::invalid_argument("_triad_bandwidth: elements and repetitions must be positive");
  std::vector<double> rates;
  {
    py::gil_scoped_release released;
    std::vector<double> a(elements, 1.0), b(elements, 2.0), c(elements, 3.0);
    for(int pass = 0; pass <= repetitions; ++pass) {
      const auto start = std::chrono::steady_clock::now();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, elements, 1 << 16),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for(std::size_t i = r.begin(); i != r.end(); ++i) a[i] = b[i] + 3.0 * c[i];
                        });
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if(pass > 0) rates.push_back(24.0 * double(elements) / seconds / 1e9);
    }
  }
  std::sort(rates.begin(), rates.end());
  return py::make_tuple(rates[rates.size() / 2], rates.back());
}

/// m.def(name, function, extra...) that also records, in `parameters` (the module's `_parameters`), each parameter
/// of the function and its default (inspect.Parameter.empty where it has none), taken from the argument objects
/// that define them. The tiled runs read there what they may pass on and what the library does by default.
template <typename Function, typename... Extra>
void def_with_parameters(py::module_& m, py::dict& parameters, const char* name, Function&& function,
                         const Extra&... extra)
{
  const py::object required = py::module_::import("inspect").attr("Parameter").attr("empty");
  py::dict defaults;
  auto record = [&](const auto& e) {
    using E = std::decay_t<decltype(e)>;
    if constexpr(std::is_same_v<E, py::arg_v>)
      defaults[e.name] = e.value ? py::object(e.value) : py::object(py::none());
    else if constexpr(std::is_same_v<E, py::arg>)
      defaults[e.name] = required;
  };
  (record(extra), ...);
  parameters[name] = defaults;
  m.def(name, std::forward<Function>(function), extra...);
}

/// The library's functions on arrays, and the table of their parameters (`_parameters`).
void bind_functions(py::module_& m)
{
  py::dict parameters; // of the library's functions, as m._parameters
  const Detail_filter filter;
  const unsigned int laplacian_k = default_laplacian_neighbors;
  const std::string default_order = setting_name(filter.order);
  const std::string default_weights = setting_name(Laplacian_weights().weighting);

  def_with_parameters(
    m, parameters, "compute_geometric_details", &bound_compute_geometric_details, "points"_a, "normals"_a = py::none(),
    py::kw_only(), "k"_a = laplacian_k, "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu,
    "weights"_a = default_weights, "progress"_a = py::none(), "neighbor_radius"_a = py::none(),
    doc("The detail vector delta = f(K) p of every point and its oriented magnitude +-|delta| (the sign of "
        "delta . n); K = I - W is the point-set Laplacian (doc/geometric_details.md).",
        {points_doc, normals_doc, filter_doc, progress_doc,
         "neighbor_radius : numpy.ndarray, optional\n    A writable contiguous (n,) float64 array that receives "
         "each point's distance to its k-th\n    nearest neighbour (the tiled runs check with it that a tile held "
         "every neighbour used)."},
        "Details\n    (details (n, 3), magnitude (n,)), new float64 arrays.")
      .c_str());
  const std::string region_doc = R"(roi : array_like of int or bool
    The region of interest: point indices, or a boolean mask of all the points.)";
  const std::string anchors_doc = R"(anchors : array_like of int or bool, optional
    Points held where they are (indices or a mask); None lets the function anchor the region's border.)";
  def_with_parameters(
    m, parameters, "scale_geometric_details",
    [](const Array_like& points, const Optional_array_like& normals, const Array_like& roi, double s,
       const Optional_array_like& anchors, long long k, const std::string& order, double lam, double mu,
       const std::string& weights, const Optional_progress& progress) {
      return manipulate(false, points, normals, roi, s, anchors, k, order, lam, mu, weights, progress);
    },
    "points"_a, "normals"_a = py::none(), py::kw_only(), "roi"_a, "s"_a, "anchors"_a = py::none(), "k"_a = laplacian_k,
    "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu, "weights"_a = default_weights,
    "progress"_a = py::none(),
    doc("The points with the details of a region scaled by s (Miao et al. 2007, Sect. 4): a least-squares "
        "solve that keeps the rest of the shape (doc/detail_scaling.md).",
        {points_doc, normals_doc, region_doc,
         "s : float\n    The scale of the details: 0 removes them, 1 keeps the points, 2 doubles them.", anchors_doc,
         filter_doc, progress_doc},
        "numpy.ndarray\n    The moved points (n, 3), a new array (the points are read once into it; the input is "
        "not changed).")
      .c_str());
  def_with_parameters(
    m, parameters, "enhance_geometric_details",
    [](const Array_like& points, const Optional_array_like& normals, double s, const Optional_array_like& roi,
       const Optional_array_like& anchors, long long k, const std::string& order, double lam, double mu,
       const std::string& weights, const Optional_progress& progress) {
      return manipulate(true, points, normals, roi, s, anchors, k, order, lam, mu, weights, progress);
    },
    "points"_a, "normals"_a = py::none(), py::kw_only(), "s"_a, "roi"_a = py::none(), "anchors"_a = py::none(),
    "k"_a = laplacian_k, "order"_a = default_order, "lam"_a = filter.lambda, "mu"_a = filter.mu,
    "weights"_a = default_weights, "progress"_a = py::none(),
    doc("The points with their details against a smooth base surface (the balanced curvature flow) enhanced by "
        "s (Miao et al. 2007, Sect. 4; doc/detail_scaling.md).",
        {points_doc, normals_doc, "s : float\n    The enhancement: 1 keeps the points, 2 doubles the details.",
         "roi : array_like of int or bool, optional\n    The region enhanced (indices or a mask); None: every point.",
         anchors_doc, filter_doc, progress_doc},
        "numpy.ndarray\n    The moved points (n, 3), a new array (the points are read once into it).")
      .c_str());
  def_with_parameters(
    m, parameters, "estimate_mean_curvature", &bound_estimate_mean_curvature, "points"_a, "normals"_a = py::none(),
    py::kw_only(), "k"_a = default_curvature_neighbors, "fitting"_a = setting_name(Curvature_fitting::closed_form),
    "progress"_a = py::none(),
    doc("The signed mean curvature of every point: a sphere with outward normals has +1/r (doc/curvature.md).",
        {points_doc, normals_doc, "k : int\n    Neighbours of each local fit (itself not counted).",
         "fitting : {\"closed_form\", \"monge\"}\n    A closed-form degree-2 fit, or CGAL's Monge jet fitting.",
         progress_doc},
        "numpy.ndarray\n    (n,) float64.")
      .c_str());
  const Simplification_settings simplification;
  def_with_parameters(
    m, parameters, "compute_simplification_sample_points", &bound_compute_simplification_sample_points, "points"_a,
    "normals"_a = py::none(), py::kw_only(), "target_count"_a = simplification.target_count,
    "max_cluster_size"_a = py::none(), "mode_threshold"_a = simplification.mode_spread_threshold,
    "k"_a = default_mean_shift_neighbors, "progress"_a = py::none(),
    doc("The simplification sample point (SSP) of every point: a 7D mean shift over position, normal and "
        "curvature, and clusters that are dense where the surface bends (doc/simplification.md).",
        {points_doc, normals_doc, "target_count : int\n    About how many sample points to make.",
         "max_cluster_size : int, optional\n    The most points a sample point may have, instead of target_count.",
         "mode_threshold : float\n    How far apart (in the mean shift's range units) two modes must be to split a "
         "cluster.",
         "k : int\n    Neighbours of the mean shift (itself not counted).", progress_doc},
        "numpy.ndarray\n    (n,) int64, the sample point of each point, 0 .. number of sample points - 1.")
      .c_str());
  const Upsampling_settings upsampling;
  def_with_parameters(
    m, parameters, "upsample_point_set", &bound_upsample_point_set, "points"_a, "normals"_a, py::kw_only(),
    "spacing"_a = upsampling.detection.spacing, "max_hole_size"_a = upsampling.detection.max_hole_size,
    "k"_a = upsampling.neighbors, "roi"_a = py::none(), "spacing_before"_a = py::none(), "progress"_a = py::none(),
    doc("New samples that fill the holes and sparse parts of an oriented point set (doc/upsampling.md).",
        {points_doc,
         "normals : (n, 3) array_like\n    Unit normals (required: the holes and the new samples' surface "
         "come from them).",
         "spacing : float\n    The spacing of the new samples; 0: each point's local spacing.",
         "max_hole_size : float\n    The widest hole filled, in spacings.",
         "k : int\n    Neighbours of the principal axes and of the local surface fits (at least 6).",
         "roi : array_like of int or bool, optional\n    Only holes next to these points are filled.",
         "spacing_before : (n,) array_like, optional\n    Each point's local spacing before an edit "
         "(local_spacing of the points it started from; needs roi): the gaps are measured against it, so that only "
         "what the edit stretched is filled (point-detail edit --upsample).",
         progress_doc},
        "Upsampled\n    (points (m, 3), normals (m, 3)), the new samples only.")
      .c_str());
  def_with_parameters(
    m, parameters, "compute_neighbor_graph", &bound_compute_neighbor_graph, "points"_a, py::kw_only(), "k"_a = 10,
    "symmetric"_a = false, "progress"_a = py::none(),
    doc("The neighbourhoods every function of the package uses: each point's closed ball of its k-th nearest other "
        "point (exactly k points, more where points tie at that distance), whatever the order of the points "
        "(doc/design.md, \"One neighbourhood rule\").",
        {points_doc, "k : int\n    Neighbours of a point, itself not counted (fewer than the points).",
         "symmetric : bool\n    The union of the graph and its transpose instead: j is a neighbour of i when either "
         "lists the other; each row sorted by index.",
         progress_doc},
        "tuple\n    (offsets (n + 1,), neighbors (m,)), int64: the neighbours of point i are "
        "neighbors[offsets[i]:offsets[i + 1]], nearest first (by index when symmetric).")
      .c_str());
  def_with_parameters(
    m, parameters, "compute_local_spacing", &bound_compute_local_spacing, "points"_a,
    doc("Each point's local spacing: the median, over the point and its 15 nearest neighbours, of their mean distance "
        "to their 6 nearest (doc/upsampling.md).",
        {points_doc}, "numpy.ndarray\n    (n,) float64.")
      .c_str());
  def_with_parameters(
    m, parameters, "refit_normals", &bound_refit_normals, "points"_a, "normals"_a, "moved"_a, py::kw_only(),
    "k"_a = default_normal_neighbors,
    doc("The normals re-fitted where points moved (after scale_geometric_details or enhance_geometric_details, as "
        "point-detail scale does): each moved point's normal and its neighbours' from a degree-2 fit, on the side of "
        "the old normal; the others kept (doc/detail_scaling.md).",
        {points_doc, "normals : (n, 3) array_like\n    The normals before the points moved.",
         "moved : array_like of int or bool\n    The points that moved (indices or a mask).",
         "k : int\n    Neighbours of a fit (at least 5)."},
        "numpy.ndarray\n    (n, 3) float64, a new array.")
      .c_str());

  def_with_parameters(
    m, parameters, "estimate_oriented_normals", &bound_estimate_oriented_normals, "points"_a, py::kw_only(),
    "k"_a = default_normal_neighbors, "progress"_a = py::none(),
    doc("Unit normals by jet fitting, oriented consistently along a minimum spanning tree (as the program "
        "estimates them for an input without normals).",
        {points_doc,
         "k : int\n    Neighbours of each point's fit, the point itself not counted; at least 5, fewer than the "
         "number of points.",
         progress_doc},
        "numpy.ndarray\n    (n, 3) float64 normals.")
      .c_str());
  m.attr("_parameters") = parameters;
}

/// The program's readers, writers, colour maps and pictures.
void bind_io(py::module_& m)
{
  m.def("record_layout", &record_layout, "path"_a,
        doc("Where the points of a binary PCD or a LAS file are, for mapping the file instead of reading it (the "
            "tiled runs): the header checked as read_points checks it.",
            {"path : str or os.PathLike\n    A .pcd (binary) or .las file."},
            "dict\n    points, data_offset, record_bytes; fields: (name, byte offset in a record, kind and bytes such "
            "as 'f4', 'i4', 'u2') of each single-valued field; coordinates and normals (field names, normals None "
            "when absent); scale and shift (coordinate = field * scale + shift).",
            false)
          .append("\nRaises\n------\nValueError\n    Another format, an ASCII or compressed PCD, or a header the "
                  "readers refuse.\n")
          .c_str());
  m.def("read_points", &read_points, "path"_a,
        doc("Reads a PLY, OFF, XYZ, PWN, PCD, PTS, PTX or LAS point set with the point-detail program's readers "
            "(doc/formats.md says what each keeps): the header is checked before anything is allocated, and a file "
            "larger than the memory, truncated or malformed is refused with the program's message "
            "(doc/bad_input.md); non-finite coordinates of a binary file are read as they are (the algorithms refuse "
            "them), except the points without position, which are left out (PCD points whose x, y and z are all "
            "NaN, PTX points 0 0 0). A mesh's normals are its faces' area-weighted vertex normals.",
            {"path : str or os.PathLike\n    The file; its extension names the format."},
            "PointSet\n    (points (n, 3) float64, normals (n, 3) or None, properties: dict of the other per-point "
            "properties, float64 (n,) each, colours as 'colors' (n, 3) uint8).",
            false)
          .append("\nRaises\n------\nFileNotFoundError\n    No such file.\nValueError\n    A file the readers "
                  "refuse, with their message.\n")
          .c_str());
  m.def("write_ply", &write_ply, "path"_a, "points"_a, "normals"_a = py::none(), "colors"_a = py::none(), py::kw_only(),
        "input_path"_a = py::none(),
        doc("Writes a binary little-endian PLY as the program does (x y z, nx ny nz, the scalars as doubles, red "
            "green blue): into a temporary file beside it, renamed once whole, so a failure leaves no partial "
            "file. Any extra keyword argument is a per-point scalar property of that name.",
            {"path : str or os.PathLike\n    The file to write.", points_doc,
             "normals : (n, 3) array_like, optional\n    Written as nx ny nz.",
             "colors : (n, 3) array_like of int, optional\n    Written as red green blue, integers in 0..255.",
             "input_path : str or os.PathLike, optional\n    The file the points were read from: writing over it is "
             "refused.",
             "**scalars : (n,) array_like\n    Per-point values, written as double properties in the order given."},
            "", true)
          .c_str());
  m.def("sequential_colors", [](const Array_like& values) { return colors_by(point_detail::sequential_colors, values); },
        "values"_a,
        doc("The program's sequential colour map (the edit's distance moved), from the 2nd to the 98th "
            "percentile of the values.",
            {"values : (n,) array_like\n    The values, e.g. each point's displacement."},
            "numpy.ndarray\n    (n, 3) uint8 colours.")
          .c_str());
  m.def("label_colors", &label_colors, "labels"_a,
        doc("The program's colours of clusters (point-detail simplify --clusters): a hash of each label spread over "
            "the hue circle, so that neighbouring labels differ.",
            {"labels : (n,) array_like of int\n    Labels >= 0, e.g. each point's sample point."},
            "numpy.ndarray\n    (n, 3) uint8 colours.")
          .c_str());
  m.def("diverging_colors",
        [](const Array_like& values, std::optional<double> limit) {
          if(!limit) return colors_by([](const std::vector<double>& v) { return point_detail::diverging_colors(v); }, values);
          if(!(*limit > 0) || !std::isfinite(*limit))
            throw std::invalid_argument("diverging_colors: limit must be positive and finite, not " +
                                        std::to_string(*limit));
          return colors_by([&](const std::vector<double>& v) { return point_detail::diverging_colors(v, *limit); },
                           values);
        },
        "values"_a, py::kw_only(), "limit"_a = py::none(),
        doc("The program's blue-white-red colour map of signed values, symmetric about zero and saturating at the "
            "98th percentile of the non-zero magnitudes (doc/geometric_details.md, \"Colour maps\").",
            {"values : (n,) array_like\n    The values, e.g. the details' magnitude.",
             "limit : float, optional\n    Saturate at +-limit instead (the tiled runs pass the whole scan's)."},
            "numpy.ndarray\n    (n, 3) uint8 colours.")
          .c_str());
  const point_detail::Render_settings render;
  m.def("render_png", &render_png, "points"_a, "normals"_a = py::none(), py::kw_only(), "values"_a = py::none(),
        "colors"_a = py::none(), "view"_a = "front", "width"_a = render.width, "height"_a = render.height,
        "splat_scale"_a = render.splat_scale, "legend"_a = py::none(),
        doc("A PNG picture of the points as the program draws it (splats with a depth buffer, shaded by the "
            "normals), e.g. for IPython.display.Image.",
            {points_doc, "normals : (n, 3) array_like, optional\n    Shade by them; None: flat shading.",
             "values : (n,) array_like, optional\n    Colour by these values (a diverging map when both signs occur, "
             "else a sequential one) with a legend of their range.",
             "colors : (n, 3) array_like of int, optional\n    Colour by these colours (0..255) instead.",
             "view : str\n    front, back, left, right, top, bottom, iso, or \"AZIMUTH,ELEVATION\" in degrees.",
             "width, height : int\n    The picture's size in pixels.",
             "splat_scale : float\n    Scales the splats' radius.",
             "legend : str, optional\n    What the values are and their unit, written over the legend's bar (e.g. "
             "\"displacement, model units\"; letters, digits, spaces and .,-+/()_)."},
            "bytes\n    The PNG file's bytes.")
          .c_str());
}

/// The library's threads, and what the tests and the benchmarks measure through the module.
void bind_threads(py::module_& m)
{
  m.def("set_num_threads", &set_num_threads, "count"_a,
        doc("Limits the library's worker threads (TBB's max_allowed_parallelism), as the program's --threads does. "
            "cgal_ext.threads(n) does the same for a with-block.",
            {"count : int or None\n    At least 1; None lifts the limit (every core)."},
            "", false)
          .c_str());
  m.def("get_num_threads", &get_num_threads, "The number of worker threads the library may use now.");
  m.def("_trace_reads", [](bool on) {
    read_trace.lowest = std::numeric_limits<std::uintptr_t>::max();
    read_trace.highest = 0;
    read_trace.on = on;
  }, "on"_a, "Tests only: start (True) or stop recording the memory the library reads through points and normals.");
  m.def("_read_span", [] { return py::make_tuple(read_trace.lowest.load(), read_trace.highest.load()); },
        "Tests only: the lowest and one past the highest address read since _trace_reads(True).");
  m.def("_triad_bandwidth", &triad_bandwidth, "elements"_a = std::size_t(40000000), "repetitions"_a = 6,
        "Benchmarks only: the memory bandwidth of STREAM's triad a[i] = b[i] + 3 c[i] over three arrays of `elements` "
        "doubles on the library's threads, in GB/s counting 24 bytes per element: the median and the best of "
        "`repetitions` passes after one untimed.");
}

/// The editing class; its constructor's keywords are the rows of deformation_keywords().
void bind_deformation(py::module_& m)
{
  std::vector<std::string> parameters = {points_doc, normals_doc};
  for(std::string& entry : deformation_keyword_docs()) parameters.push_back(std::move(entry));
  py::class_<Deformation> deformation(
    m, "Deformation",
    doc("Detail-preserving editing of a point set (Miao et al. 2007, Sect. 6), shaped like CGAL's "
        "Surface_mesh_deformation: select a region of interest and handle groups, preprocess(), "
        "then per frame of a drag set_handle_transform(), deform() and diffuse(), and "
        "restore_details() once the drag ends (doc/editing.md). The points and normals are "
        "copied at construction. The settings are keyword-only; `settings` reads them back.",
        parameters, "", true)
      .c_str());
  {
    // The keywords arrive as **kwargs, so the signature line help() shows is written from the rows instead.
    py::options written_signature;
    written_signature.disable_function_signatures();
    deformation.def(
      py::init([](const py::args& args, const py::kwargs& kwargs) {
        // The points and the normals by position or by keyword; every other keyword is a setting.
        if(args.size() > 2)
          throw py::type_error("Deformation() takes the points and the normals by position and its settings by "
                               "keyword (" +
                               std::to_string(args.size()) + " positional arguments given)");
        py::dict settings(kwargs);
        const auto argument = [&](const char* name, std::size_t position) -> py::object {
          const bool by_keyword = settings.contains(name);
          if(by_keyword && args.size() > position)
            throw py::type_error(std::string("Deformation() got two values for ") + name);
          if(by_keyword) return settings.attr("pop")(name);
          if(args.size() > position) return args[position];
          if(position == 0) throw py::type_error("Deformation() needs the points");
          return py::none();
        };
        const py::object points = argument("points", 0), normals = argument("normals", 1);
        return std::make_unique<Deformation>(Array_like(points), Optional_array_like(normals),
                                             deformation_settings(settings));
      }),
      (deformation_signature() + "\n\nThe parameters are the class's (help(cgal_ext.Deformation)).").c_str());
  }
  m.attr("_parameters")["Deformation"] = deformation_defaults(); // beside the functions' (bind_functions)
  deformation
    .def("insert_roi", &Deformation::insert_roi, "indices"_a,
         doc("Adds points to the region of interest (the part that deforms).",
             {"indices : array_like of int or bool\n    Point indices, or a boolean mask of all the points."}, "", true)
           .c_str())
    .def(
      "create_handle_group", &Deformation::create_handle_group, "indices"_a = py::none(),
      doc("Adds a handle group (points moved together by one rigid transform; they must lie in the region).",
          {"indices : array_like of int or bool, optional\n    Its points (indices or a mask); more can be added with "
           "insert_handle_points()."},
          "int\n    The group's number.", true)
        .c_str())
    .def("insert_handle_points", &Deformation::insert_handle_points, "group"_a, "indices"_a,
         doc("Adds points to a handle group.",
             {"group : int\n    A group create_handle_group() returned.",
              "indices : array_like of int or bool\n    Point indices, or a boolean mask of all the points."},
             "", true)
           .c_str())
    .def("clear_selection", &Deformation::clear_selection,
         "Empties the region of interest and removes every handle group (the next deform() preprocesses again).")
    .def("preprocess", &Deformation::preprocess, py::kw_only(), "progress"_a = py::none(),
         doc("Makes the sample points of the selection, their Laplacian and details, the strength field and the "
             "diffusion stencils, and factors the least squares; deform() calls it when the selection changed.",
             {progress_doc}, "bool\n    True (a cancelled call raises instead).", true)
           .c_str())
    .def("analyse_points", &Deformation::analyse_points, py::kw_only(), "progress"_a = py::none(),
         doc("Computes now what preprocess() needs whatever the selection (the points' mean-shift modes, the "
             "clustering's most costly part), so that it can run while a user selects; preprocess() computes it "
             "when it has not been. Safe to call in another thread while the selection is changed.",
             {progress_doc}, "bool\n    True (a cancelled run raises).")
           .c_str())
    .def(
      "set_handle_transform", &Deformation::set_handle_transform, "group"_a, "rotation"_a = py::none(),
      "translation"_a = py::none(), py::kw_only(), "transform"_a = py::none(), "pivot"_a = py::none(),
      doc("Sets the rigid motion of a handle group: p -> R (p - c) + c + t (c = pivot, 0 when not given), or the "
          "4x4 matrix [[R, t], [0, 0, 0, 1]].",
          {"group : int\n    The handle group.",
           "rotation : (3, 3) array_like, optional\n    R, a rotation "
           "(orthonormal within 1e-6, determinant +1); None: the identity.",
           "translation : (3,) array_like, optional\n    t; None: zero.",
           "transform : (4, 4) array_like, optional\n    The whole rigid motion instead of rotation, translation and "
           "pivot.",
           "pivot : (3,) array_like, optional\n    The point the rotation turns about."},
          "", true)
        .c_str())
    .def("deform", &Deformation::deform, py::kw_only(), "progress"_a = py::none(),
         doc("Solves the sample points' new positions for the handles' transforms (preprocessing first when the "
             "selection changed): one back-substitution per call.",
             {progress_doc}, "", true)
           .c_str())
    .def(
      "diffuse", &Deformation::diffuse, "points_out"_a = py::none(), "normals_out"_a = py::none(),
      doc("Carries the sample points' deformation to every point and normal.",
          {"points_out : (n, 3) float64 ndarray, optional\n    Written in place (reuse it from drag to drag); None: a "
           "new array.",
           "normals_out : (n, 3) float64 ndarray, optional\n    The same for the normals."},
          "Deformed\n    (points, normals) in the input order: points_out and normals_out when given.", true)
        .c_str())
    .def("restore_details", &Deformation::restore_details, "points_out"_a = py::none(), "normals_out"_a = py::none(),
         doc("After diffuse(): puts back the fine details the diffusion smoothed (conjugate gradients, at most "
             "detail_iterations; call it once a drag ends), then returns the points and normals as diffuse() does.",
             {"points_out : (n, 3) float64 ndarray, optional\n    Written in place; None: a new array.",
              "normals_out : (n, 3) float64 ndarray, optional\n    The same for the normals."},
             "Deformed\n    (points, normals) in the input order.", true)
           .c_str())
    .def(
      "reset", &Deformation::reset,
      "Handle transforms back to the identity and every point back to its input position; the preprocessing is kept.")
    .def("sample_point_of", &Deformation::sample_point_of, "points"_a,
         doc("The sample point of points (after preprocess()).",
             {"points : int or array_like of int or bool\n    A point index, or indices or a boolean mask."},
             "int or numpy.ndarray\n    The sample point of each, int64.", true)
           .c_str())
    .def("number_of_handle_groups", &Deformation::number_of_handle_groups, "The number of handle groups.")
    .def("number_of_sample_points", &Deformation::number_of_sample_points,
         "The number of sample points (0 before preprocess()).")
    .def("is_preprocessed", &Deformation::is_preprocessed, "Whether preprocess() ran since the selection last changed.")
    .def("renderer_setup", &Deformation::renderer_setup,
         "What a renderer that moves the points itself (a GPU) needs once per preprocessing, in input order: each\n"
         "point's stencil (``stencil_samples`` (n, m) int32 and ``stencil_weights`` (n, m) float32), ``exact_handle``\n"
         "(n,) int8, and the collar: ``collar_points`` (c,), their ``collar_slots`` and ``collar_weights`` (c, 2)\n"
         "(slot -1: none) into ``collar_handles``, the handle points whose steps the collar spreads.")
    .def("renderer_frame", &Deformation::renderer_frame,
         "Per drag, after deform(): one float32 array of each sample point's motion (3x4, row-major: a point p it\n"
         "carries alone moves by M (p, 1)), each handle group's transform (3x4) and each collar handle point's\n"
         "step (position, then normal; 6 numbers). O(sample points): what a renderer's shader blends per point.")
    .def("diffusion_state", &Deformation::diffusion_state,
         "After deform(): the sample points' side of the drag, as a dict of ``sample_positions`` and\n"
         "``deformed_sample_positions`` (s, 3), ``motions`` (s, 3, 4: a point p carried by sample point j alone moves\n"
         "by motions[j] @ (p, 1)), ``region_samples`` (s,), ``handle_transforms`` (g, 7: quaternion w, x, y, z and\n"
         "translation), ``stencil_size``, ``origin``, ``portable``, ``exact_handles``, ``collar_reach`` and the\n"
         "restoration's settings ``detail_anchor``, ``detail_iterations`` and ``detail_tolerance``, with the\n"
         "Chebyshev steps they give (``detail_steps``, read only: a point's restored position depends on the points\n"
         "that many hops away): what diffuse_points() needs to move points this deformation was not built on, in\n"
         "this process or another (a tiled edit's workers).")
    .def("statistics", &Deformation::statistics, "Sizes and timings of the last calls, as a dict.")
    .def_property_readonly("settings", &Deformation::settings, "The settings, under the constructor's keyword names.")
    .def("__len__", &Deformation::size)
    .def("__repr__", &Deformation::repr);
  m.def("_read_edit", &read_edit, "path"_a, "points"_a,
        "The program's reading of an edit JSON with its selections evaluated on the points: a dict of ``roi``\n"
        "(int64 indices), ``handles`` (per group a dict of ``points``, ``rotation`` (3, 3) and ``translation``) and\n"
        "``settings`` (Deformation's keywords). A file the program refuses is a ValueError with its message.");
  m.def("diffuse_points", &bound_diffuse_points, "points"_a, "normals"_a, "state"_a, py::kw_only(),
        "selection"_a = py::none(), "restore_details"_a = false, "neighbor_radius"_a = py::none(),
        "Moves points a Deformation was not built on (a denser sampling of the same surface, a tile of a larger\n"
        "scan) as its diffuse() moves its own: each by its ``stencil_size`` nearest sample points' motions, weighted\n"
        "as diffuse() weights them; with ``selection``, the exact handle points onto their group's transform and\n"
        "the region's points within ``collar_reach`` of a handle by the handle's step. The deformation's own\n"
        "points with their selection move as diffuse() moves them, bit for bit; a part of a scan moves as the whole\n"
        "would wherever it holds the handle points within the collar's reach. With ``restore_details``, the fine\n"
        "details the blend smooths out are then put back as Deformation.restore_details() puts them (the\n"
        "deformation's own points: bit for bit; a part of a scan: as the whole where it holds every point within\n"
        "the restoration's steps' hops).\n\n"
        "Parameters\n----------\npoints, normals : array_like\n    (n, 3) float64.\n"
        "state : dict\n    Deformation.diffusion_state(), after deform().\n"
        "selection : array_like of int, optional\n    Per point: -2 outside the region of interest, -1 in it, or its "
        "handle group. Without it,\n    every point is a region point that is no handle.\n"
        "restore_details : bool\n    Whether to put back the fine details too (the state's detail_* settings).\n"
        "neighbor_radius : numpy.ndarray, optional\n    A writable contiguous (n,) float64 array that receives each "
        "point's distance to its 10th\n    nearest other point (the restoration's neighbourhoods).\n\n"
        "Returns\n-------\nDeformed\n    (points (n, 3), normals (n, 3)), new float64 arrays.");
}

} // namespace

PYBIND11_MODULE(_core, m)
{
  m.doc() = "The compiled part of cgal_ext: high-frequency geometric details of point-sampled surfaces (Miao et al. "
            "2007) on numpy arrays.";
  m.attr("__version__") = CGAL_EXT_VERSION;
  // The library's exceptions: Invalid_input is a std::invalid_argument (ValueError), Numerical_failure a
  // std::runtime_error (RuntimeError); pybind11 translates both with their messages.
  result_types.details = named_tuple(m, "Details", {"details", "magnitude"},
                                     "Details(details, magnitude): the detail vector of every point (n, 3) and its "
                                     "oriented magnitude (n,), positive where the detail stands out along the normal.");
  result_types.upsampled = named_tuple(m, "Upsampled", {"points", "normals"},
                                       "Upsampled(points, normals): the new samples (m, 3) and their normals (m, 3).");
  result_types.deformed = named_tuple(m, "Deformed", {"points", "normals"},
                                      "Deformed(points, normals): every point's and normal's deformed position (n, 3), "
                                      "in the input order.");
  result_types.point_set =
    named_tuple(m, "PointSet", {"points", "normals", "properties"},
                "PointSet(points, normals, properties): the points (n, 3) float64, their normals "
                "(n, 3) or None, and the other per-point properties by name (float64 arrays; "
                "colours as 'colors', (n, 3) uint8).");

  bind_functions(m);
  bind_io(m);
  bind_threads(m);
  bind_deformation(m);
}
