// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// Settings by name and the named results.
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_SETTINGS_H
#define CGAL_EXT_PYTHON_SETTINGS_H

namespace {

// ---- settings -----------------------------------------------------------------------------------------------

/// A setting's value from the name a keyword argument gives (the library's `Setting_names`, shared with the edit
/// files and the program's options).
template <typename Enum>
Enum parse_setting(const std::string& name, const char* setting)
{
  Enum value{};
  if(!CGAL_ext::find_setting(name, value))
    throw py::value_error(std::string(setting) + " must be one of " + CGAL_ext::setting_choices<Enum>() + ", not \"" +
                          name + "\"");
  return value;
}

using namespace CGAL_ext;

Detail_settings detail_settings(const std::string& order, double lam, double mu, const std::string& weights)
{
  Detail_settings s(Detail_filter{parse_setting<Detail_order>(order, "order"), lam, mu});
  s.weights.weighting = parse_setting<Laplacian_weighting>(weights, "weights");
  s.validate();
  return s;
}

/// A count given from Python (k, iterations, sizes); the library checks its own lower bounds.
unsigned int as_count(long long value, const char* argument)
{
  if(value < 0 || value > std::numeric_limits<int>::max())
    throw py::value_error(std::string(argument) + " must be a count >= 0, not " + std::to_string(value));
  return unsigned(value);
}

/// A size given from Python that must be at least 1 (target counts, cluster sizes).
std::size_t as_size(long long value, const char* argument)
{
  if(value < 1) throw py::value_error(std::string(argument) + " must be at least 1, not " + std::to_string(value));
  return std::size_t(value);
}

// ---- named results ----------------------------------------------------------------------------------------------

/// The named tuples of the results, made once at import (kept for the life of the process).
struct Result_types
{
  py::handle details, upsampled, deformed, point_set;
};
Result_types result_types;

py::handle named_tuple(py::module_& m, const char* name, std::vector<std::string> fields, const char* doc)
{
  py::object type = py::module_::import("collections").attr("namedtuple")(name, fields, "module"_a = "cgal_ext");
  type.attr("__doc__") = doc;
  m.attr(name) = type;
  return type.release();
}

/// `body()` with the program's Cli_error (a bad file, a bad view) raised as the ValueError a Python user expects,
/// with the program's message.
template <typename Body>
auto translating_program_errors(Body&& body)
{
  try {
    return body();
  } catch(const point_detail::Cli_error& e) {
    throw py::value_error(e.what());
  }
}

} // namespace

#endif // CGAL_EXT_PYTHON_SETTINGS_H
