// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_EXCEPTIONS_H
#define CGAL_EXT_EXCEPTIONS_H

#include <stdexcept>
#include <string>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Thrown by every public entry point when the caller's input cannot be processed: an empty or too small
  range, non-finite coordinates, invalid filter parameters, ... The message says what was wrong and what to do.
  Unlike CGAL's preconditions, these checks are active in release builds.
*/
class Invalid_input : public std::invalid_argument
{
public:
  explicit Invalid_input(const std::string& what) : std::invalid_argument(what) {}
};

/*!
  \ingroup PkgCGALExtRef
  Thrown when a factorisation or a solve fails numerically although the input passed validation.
*/
class Numerical_failure : public std::runtime_error
{
public:
  explicit Numerical_failure(const std::string& what) : std::runtime_error(what) {}
};

} // namespace CGAL_ext

#endif // CGAL_EXT_EXCEPTIONS_H
