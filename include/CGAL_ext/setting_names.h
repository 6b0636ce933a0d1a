// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_SETTING_NAMES_H
#define CGAL_EXT_SETTING_NAMES_H

#include <cstddef>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  One spelling of a value of the enum setting `Enum`: the edit files, the program's options, its reports and the
  Python package all read and write the values of a setting by these names. The first spelling of a value is its
  name; a later one (`older`) is an older spelling still read.
*/
template <typename Enum>
struct Setting_spelling
{
  const char* name;
  Enum value;
  bool older = false;
};

/*!
  \ingroup PkgCGALExtRef
  The spellings of the enum `Enum`, specialised beside each enum setting as
  `static constexpr Setting_spelling<Enum> table[]`.
*/
template <typename Enum>
struct Setting_names;

/// The name of `value` (its first spelling).
template <typename Enum>
const char* setting_name(Enum value)
{
  for(const Setting_spelling<Enum>& s : Setting_names<Enum>::table)
    if(s.value == value) return s.name;
  return "?";
}

/// The names a setting of type `Enum` takes, older spellings left out.
template <typename Enum>
std::vector<std::string> setting_names()
{
  std::vector<std::string> names;
  for(const Setting_spelling<Enum>& s : Setting_names<Enum>::table)
    if(!s.older) names.push_back(s.name);
  return names;
}

/// `"a", "b" or "c"`: the names of a setting, for messages.
template <typename Enum>
std::string setting_choices()
{
  const std::vector<std::string> names = setting_names<Enum>();
  std::string choices;
  for(std::size_t i = 0; i < names.size(); ++i)
    choices += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + ("\"" + names[i] + "\"");
  return choices;
}

/// Whether `name` spells a value of `Enum` (its name or an older spelling), which it then writes to `value`.
template <typename Enum>
bool find_setting(const std::string& name, Enum& value)
{
  for(const Setting_spelling<Enum>& s : Setting_names<Enum>::table)
    if(name == s.name) {
      value = s.value;
      return true;
    }
  return false;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_SETTING_NAMES_H
