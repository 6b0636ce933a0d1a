// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// The settings of the editing class, one row per keyword of Deformation's constructor. The rows alone define the
// keywords: the constructor parses them, and its signature line, its docstring, `Deformation.settings` and
// `_parameters["Deformation"]` are written from them (a test compares the stub with the signature).
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_DEFORMATION_SETTINGS_H
#define CGAL_EXT_PYTHON_DEFORMATION_SETTINGS_H

namespace {

using Deformation_settings = Detail_preserving_deformation_settings;

/// How a keyword of type T reads from and writes to Python: the type help() shows, the type numpydoc shows.
template <typename T, typename = void>
struct Keyword_conversion;

/// `value` as T, or a TypeError naming the keyword and the type it must be: an int is a Python integer (an
/// object with __index__), a float any real number, a str a str; a bool is none of them.
template <typename T>
T keyword_cast(const py::handle& value, const char* keyword, const char* type)
{
  const auto refuse = [&] {
    return py::type_error(std::string(keyword) + " must be " + type + ", not " +
                          std::string(py::str(py::type::of(value).attr("__name__"))));
  };
  if(PyBool_Check(value.ptr()) || py::isinstance(value, py::module_::import("numpy").attr("bool_"))) throw refuse();
  if constexpr(std::is_same_v<T, std::string>) {
    if(!py::isinstance<py::str>(value)) throw refuse();
    return value.cast<std::string>();
  } else if constexpr(std::is_integral_v<T>) {
    PyObject* index = PyNumber_Index(value.ptr());
    if(!index) {
      PyErr_Clear();
      throw refuse();
    }
    int overflow = 0;
    const long long integer = PyLong_AsLongLongAndOverflow(index, &overflow);
    Py_DECREF(index);
    if(overflow) throw py::value_error(std::string(keyword) + " is out of range");
    return T(integer);
  } else {
    try {
      return value.cast<T>();
    } catch(const py::cast_error&) {
      throw refuse();
    }
  }
}

template <>
struct Keyword_conversion<double>
{
  static std::string type() { return "float"; }
  static std::string doc_type() { return "float"; }
  static py::object to_python(double v) { return py::float_(v); }
  static double from_python(const py::handle& v, const char* keyword)
  {
    return keyword_cast<double>(v, keyword, "a float");
  }
};

/// Counts (neighbours, iterations): the library checks its own lower bounds.
template <>
struct Keyword_conversion<unsigned int>
{
  static std::string type() { return "int"; }
  static std::string doc_type() { return "int"; }
  static py::object to_python(unsigned int v) { return py::int_(v); }
  static unsigned int from_python(const py::handle& v, const char* keyword)
  {
    return as_count(keyword_cast<long long>(v, keyword, "an int"), keyword);
  }
};

/// Sizes that must be at least 1 (target_count).
template <>
struct Keyword_conversion<std::size_t>
{
  static std::string type() { return "int"; }
  static std::string doc_type() { return "int"; }
  static py::object to_python(std::size_t v) { return py::int_(v); }
  static std::size_t from_python(const py::handle& v, const char* keyword)
  {
    return as_size(keyword_cast<long long>(v, keyword, "an int"), keyword);
  }
};

/// Optional sizes (max_cluster_size): None leaves them unset.
template <>
struct Keyword_conversion<std::optional<std::size_t>>
{
  static std::string type() { return "Optional[int]"; }
  static std::string doc_type() { return "int, optional"; }
  static py::object to_python(const std::optional<std::size_t>& v) { return v ? py::object(py::int_(*v)) : py::none(); }
  static std::optional<std::size_t> from_python(const py::handle& v, const char* keyword)
  {
    if(v.is_none()) return std::nullopt;
    return Keyword_conversion<std::size_t>::from_python(v, keyword);
  }
};

/// Enum settings, by the names the edit files and the program's options use.
template <typename Enum>
struct Keyword_conversion<Enum, std::enable_if_t<std::is_enum_v<Enum>>>
{
  static std::string type() { return "str"; }
  static std::string doc_type()
  {
    std::string choices;
    for(const std::string& name : setting_names<Enum>()) choices += (choices.empty() ? "{\"" : ", \"") + name + "\"";
    return choices + "}";
  }
  static py::object to_python(Enum v) { return py::str(setting_name(v)); }
  static Enum from_python(const py::handle& v, const char* keyword)
  {
    return parse_setting<Enum>(keyword_cast<std::string>(v, keyword, "a str"), keyword);
  }
};

/// One keyword of Deformation's constructor.
struct Deformation_keyword
{
  const char* name;
  std::string type;     ///< as the signature line and the stub show it
  std::string doc_type; ///< as the docstring's numpydoc shows it
  const char* doc;
  /// Its value in `settings`; empty for an older spelling, which is read and never written back (default None).
  std::function<py::object(const Deformation_settings&)> get;
  std::function<void(Deformation_settings&, const py::handle&)> set;
};

/// The row of the keyword `name` for the field `field(settings)` (a lambda taking `auto&`).
template <typename Field>
Deformation_keyword keyword(const char* name, const char* doc, Field field)
{
  using T = std::decay_t<decltype(field(std::declval<Deformation_settings&>()))>;
  using Conversion = Keyword_conversion<T>;
  return {name,
          Conversion::type(),
          Conversion::doc_type(),
          doc,
          [field](const Deformation_settings& s) { return Conversion::to_python(field(s)); },
          [field, name](Deformation_settings& s, const py::handle& v) { field(s) = Conversion::from_python(v, name); }};
}

/// The keywords in the order of the signature.
const std::vector<Deformation_keyword>& deformation_keywords()
{
  using S = Deformation_settings;
  static const std::vector<Deformation_keyword> rows = {
    keyword(
      "order", "The transfer function f(K) of the details, as in compute_geometric_details.",
      [](auto& s) -> auto& { return s.filter.order; }),
    keyword(
      "lam", "Its pass-band frequency, 0 < lam < mu.", [](auto& s) -> auto& { return s.filter.lambda; }),
    keyword(
      "mu", "Its highest frequency (unused by \"linear\").", [](auto& s) -> auto& { return s.filter.mu; }),
    keyword(
      "k", "Neighbours of the sample points' Laplacian.", [](auto& s) -> auto& { return s.sample_neighbors; }),
    keyword(
      "handle_weight", "inf: handles are hard constraints; else their weight in the least squares.",
      [](auto& s) -> auto& { return s.handle_weight; }),
    keyword(
      "rotations", "How the details turn: by the strength field, fitted as rigid as possible (\"arap\"), or not.",
      [](auto& s) -> auto& { return s.rotations; }),
    keyword(
      "rigid_iterations", "Local/global iterations per step in \"arap\" mode.",
      [](auto& s) -> auto& { return s.rigid_iterations; }),
    keyword(
      "rigid_rotation_smoothing", "SRE-ARAP's smooth-rotation weight (0: plain ARAP).",
      [](auto& s) -> auto& { return s.rigid_rotation_smoothing; }),
    keyword(
      "rigid_rotation_smoothing_scale", "How that weight is scaled.",
      [](auto& s) -> auto& { return s.rigid_rotation_smoothing_scale; }),
    keyword(
      "rigid_edge_weights", "Edge weights of the \"arap\" energy.",
      [](auto& s) -> auto& { return s.rigid_edge_weights; }),
    keyword(
      "strength_distance", "The distance of the strength field.", [](auto& s) -> auto& { return s.strength_distance; }),
    keyword(
      "target_count", "About how many sample points to make.",
      [](auto& s) -> auto& { return s.simplification.target_count; }),
    keyword(
      "max_cluster_size", "The most points per sample point, instead of target_count.",
      [](auto& s) -> auto& { return s.simplification.max_cluster_size; }),
    keyword(
      "diffusion_samples", "Sample points blended per point by the diffusion.",
      [](auto& s) -> auto& { return s.diffusion_samples; }),
    keyword(
      "diffusion_origin", "Where each point's offset is taken from.",
      [](auto& s) -> auto& { return s.diffusion_origin; }),
    keyword(
      "diffusion_turn", "How each sample point carries its points.", [](auto& s) -> auto& { return s.diffusion_turn; }),
    keyword(
      "detail_iterations", "The most Chebyshev steps of restore_details().",
      [](auto& s) -> auto& { return s.detail_iterations; }),
    keyword(
      "detail_tolerance", "The error reduction its steps guarantee.",
      [](auto& s) -> auto& { return s.detail_tolerance; }),
    keyword(
      "detail_anchor", "How strongly it keeps the diffusion's coarse shape.",
      [](auto& s) -> auto& { return s.detail_anchor; }),
    {"strength", "Optional[str]", "str, optional", "The older spelling of strength_distance, still read.", nullptr,
     [](S& s, const py::handle& v) {
       if(!v.is_none()) s.strength_distance = Keyword_conversion<Strength_distance>::from_python(v, "strength");
     }}};
  return rows;
}

/// The settings the keywords give (the others keep their defaults), validated; a TypeError names a keyword that
/// is none (and the one nearest to it).
Deformation_settings deformation_settings(const py::dict& kwargs)
{
  const auto& rows = deformation_keywords();
  py::list names;
  for(const Deformation_keyword& row : rows) names.append(row.name);
  std::string unknown;
  for(const auto& item : kwargs) {
    if(names.contains(item.first)) continue;
    const std::string given = py::str(item.first);
    const py::list near = py::module_::import("difflib").attr("get_close_matches")(item.first, names, 1);
    unknown += (unknown.empty() ? "'" : "; '") + given + "'" +
               (near.empty() ? std::string() : " (did you mean '" + std::string(py::str(near[0])) + "'?)");
  }
  if(!unknown.empty()) throw py::type_error("Deformation() takes no keyword argument " + unknown);
  if(kwargs.contains("strength") && !kwargs["strength"].is_none() && kwargs.contains("strength_distance"))
    throw py::value_error("give strength_distance (strength is its older spelling), not both");
  Deformation_settings s;
  for(const Deformation_keyword& row : rows)
    if(kwargs.contains(row.name)) row.set(s, kwargs[row.name]);
  s.validate();
  return s;
}

/// The settings under the constructor's keywords (the older spellings left out).
py::dict deformation_settings_dict(const Deformation_settings& s)
{
  py::dict values;
  for(const Deformation_keyword& row : deformation_keywords())
    if(row.get) values[row.name] = row.get(s);
  return values;
}

/// {keyword: default} of the constructor, None for an older spelling, as `_parameters` records functions.
py::dict deformation_defaults()
{
  const Deformation_settings defaults;
  py::dict parameters;
  parameters["points"] = py::module_::import("inspect").attr("Parameter").attr("empty");
  parameters["normals"] = py::none();
  for(const Deformation_keyword& row : deformation_keywords())
    parameters[row.name] = row.get ? row.get(defaults) : py::none();
  return parameters;
}

/// The constructor's signature line as pybind11 writes one (which it cannot here: the keywords come as **kwargs).
std::string deformation_signature()
{
  const Deformation_settings defaults;
  std::string signature = "__init__(self: cgal_ext._core.Deformation, points: numpy.typing.ArrayLike, "
                          "normals: Optional[numpy.typing.ArrayLike] = None, *";
  for(const Deformation_keyword& row : deformation_keywords())
    signature += std::string(", ") + row.name + ": " + row.type + " = " +
                 (row.get ? std::string(py::repr(row.get(defaults))) : "None");
  return signature + ") -> None";
}

/// The keywords' entries of numpydoc's Parameters section.
std::vector<std::string> deformation_keyword_docs()
{
  std::vector<std::string> entries;
  for(const Deformation_keyword& row : deformation_keywords())
    entries.push_back(std::string(row.name) + " : " + row.doc_type + "\n    " + row.doc);
  return entries;
}

} // namespace

#endif // CGAL_EXT_PYTHON_DEFORMATION_SETTINGS_H
