// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// Arrays as users have them: the types help() shows, float64 views in place, conversions, masks and indices.
// A part of cgal_ext_module.cpp, the package's one translation unit, which includes its parts in order.
#ifndef CGAL_EXT_PYTHON_ARRAYS_H
#define CGAL_EXT_PYTHON_ARRAYS_H

// ---- names the signatures show --------------------------------------------------------------------------------
// Arguments and results are Python objects checked by hand (the messages name the argument); these wrappers only
// give help() and the stub the types a user passes, instead of `object`.
#define CGAL_EXT_PYTHON_TYPE(Type, Name)                                                                      \
  struct Type : py::object                                                                                   \
  {                                                                                                          \
    Type() = default;                                                                                        \
    Type(py::object o) : py::object(std::move(o)) {}                                                         \
  };                                                                                                         \
  namespace pybind11 { namespace detail {                                                                    \
  template <>                                                                                                \
  struct type_caster<Type>                                                                                   \
  {                                                                                                          \
    PYBIND11_TYPE_CASTER(Type, const_name(Name));                                                            \
    bool load(handle source, bool)                                                                           \
    {                                                                                                        \
      value = Type(reinterpret_borrow<object>(source));                                                      \
      return true;                                                                                           \
    }                                                                                                        \
    static handle cast(const Type& source, return_value_policy, handle) { return source.inc_ref(); }         \
  };                                                                                                         \
  }}

CGAL_EXT_PYTHON_TYPE(Array_like, "numpy.typing.ArrayLike")
CGAL_EXT_PYTHON_TYPE(Optional_array_like, "Optional[numpy.typing.ArrayLike]")
CGAL_EXT_PYTHON_TYPE(Optional_progress, "Optional[Callable[[float], object]]")
CGAL_EXT_PYTHON_TYPE(Optional_int, "Optional[int]")
CGAL_EXT_PYTHON_TYPE(Optional_path, "Optional[Union[str, os.PathLike]]")
CGAL_EXT_PYTHON_TYPE(Path_like, "Union[str, os.PathLike]")
CGAL_EXT_PYTHON_TYPE(Ndarray, "numpy.ndarray")
CGAL_EXT_PYTHON_TYPE(Details_result, "Details")
CGAL_EXT_PYTHON_TYPE(Upsampled_result, "Upsampled")
CGAL_EXT_PYTHON_TYPE(Deformed_result, "Deformed")
CGAL_EXT_PYTHON_TYPE(Point_set_result, "PointSet")
CGAL_EXT_PYTHON_TYPE(Sample_points_of, "Union[int, numpy.ndarray]")


namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Index_range = boost::iterator_range<boost::counting_iterator<std::size_t>>;

// ---- arrays -----------------------------------------------------------------------------------------------------

/// An (n, 3) float64 array seen in place: row i, column c at `data + i * row_stride + c * column_stride` bytes.
struct Rows3
{
  char* data = nullptr;
  py::ssize_t rows = 0, row_stride = 0, column_stride = 0;

  double& at(std::size_t i, int c) const
  {
    return *reinterpret_cast<double*>(data + py::ssize_t(i) * row_stride + c * column_stride);
  }
};

/// Whether `rows` are contiguous rows of three aligned doubles, as a C-ordered (n, 3) float64 array's.
inline bool is_c_contiguous(const Rows3& rows)
{
  return rows.row_stride == py::ssize_t(3 * sizeof(double)) && rows.column_stride == py::ssize_t(sizeof(double)) &&
         reinterpret_cast<std::uintptr_t>(rows.data) % alignof(double) == 0;
}

/// The span of memory the library read through the points' and normals' maps since `_trace_reads(True)`: how the
/// tests see that an input is read in place, not copied (off by default; one relaxed load per read).
struct Read_trace
{
  std::atomic<bool> on{false};
  std::atomic<std::uintptr_t> lowest{std::numeric_limits<std::uintptr_t>::max()}, highest{0};

  void note(const void* first, const void* last)
  {
    const auto lo = reinterpret_cast<std::uintptr_t>(first), hi = reinterpret_cast<std::uintptr_t>(last);
    for(std::uintptr_t seen = lowest.load(); lo < seen && !lowest.compare_exchange_weak(seen, lo);) {
    }
    for(std::uintptr_t seen = highest.load(); hi > seen && !highest.compare_exchange_weak(seen, hi);) {
    }
  }
};
Read_trace read_trace;

std::string shape_of(const py::array& array)
{
  std::string s = "(";
  for(py::ssize_t d = 0; d < array.ndim(); ++d) s += (d ? ", " : "") + std::to_string(array.shape(d));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

std::string dtype_name(const py::array& array) { return py::str(array.dtype()); }

/// Whether every element of `array` lies at an address its type's alignment divides (not so in a view of a buffer
/// at an odd offset, `np.frombuffer(b, offset=4)`), as the library's reads through typed pointers need.
bool is_aligned(const py::array& array)
{
  const auto alignment = py::ssize_t(array.itemsize());
  if(reinterpret_cast<std::uintptr_t>(array.data()) % std::uintptr_t(alignment) != 0) return false;
  for(py::ssize_t d = 0; d < array.ndim(); ++d)
    if(array.strides(d) % alignment != 0) return false;
  return true;
}

/// Flags of `py::array_t<T, ...>::ensure` that copy an array whose elements are not aligned.
constexpr int aligned_copy = py::detail::npy_api::NPY_ARRAY_ALIGNED_;

/// `object` as a numpy array, or a ValueError naming `argument` and `what` it must be.
py::array as_array(const py::handle& object, const char* argument, const std::string& what)
{
  if(py::isinstance<py::array>(object)) return py::reinterpret_borrow<py::array>(object);
  try {
    return py::module_::import("numpy").attr("asarray")(object);
  } catch(py::error_already_set& e) {
    throw py::value_error(std::string(argument) + " must be " + what + " (" + e.what() + ")");
  }
}

/// An (n, 3) array of real numbers as float64: the caller's own array when it is float64 (compared by value, so
/// an array that went through pickle is one too) and aligned, else one converted copy (float32, integers, nested
/// lists, a float64 view at an odd offset).
py::array float64_rows3(const py::handle& object, const char* argument)
{
  const py::array array = as_array(object, argument, "an (n, 3) array of numbers");
  const char kind = array.dtype().kind();
  if(kind != 'f' && kind != 'i' && kind != 'u')
    throw py::value_error(std::string(argument) + " must hold real numbers (float64, float32 or integers), not dtype " +
                          dtype_name(array));
  if(array.ndim() != 2 || array.shape(1) != 3)
    throw py::value_error(std::string(argument) + " must have shape (n, 3), not " + shape_of(array));
  if(array.dtype().equal(py::dtype::of<double>()) && is_aligned(array)) return array;
  return array.attr("astype")(py::dtype::of<double>());
}

Rows3 view_of(const py::array& array)
{
  return Rows3{static_cast<char*>(const_cast<void*>(array.data())), array.shape(0), array.strides(0), array.strides(1)};
}

/// A new C-ordered (rows, 3) float64 array, and its view.
std::pair<py::array_t<double>, Rows3> new_rows3(std::size_t rows)
{
  py::array_t<double> array({py::ssize_t(rows), py::ssize_t(3)});
  return {array, view_of(array)};
}

/// `object` when it is a writable (n, 3) float64 array (checked, ValueError naming `argument`), else a new one.
std::pair<py::array, Rows3> output_rows3(const py::object& object, const char* argument, std::size_t n)
{
  if(object.is_none()) return new_rows3(n);
  if(!py::isinstance<py::array>(object))
    throw py::value_error(std::string(argument) + " must be a numpy array of shape (" + std::to_string(n) +
                          ", 3) and dtype float64");
  const auto array = py::reinterpret_borrow<py::array>(object);
  if(array.ndim() != 2 || array.shape(1) != 3 || std::size_t(array.shape(0)) != n)
    throw py::value_error(std::string(argument) + " must have " + std::to_string(n) + " rows and 3 columns, not shape " +
                          shape_of(array));
  if(!array.dtype().equal(py::dtype::of<double>()))
    throw py::value_error(std::string(argument) + " must have dtype float64, not " + dtype_name(array));
  if(!array.writeable()) throw py::value_error(std::string(argument) + " is not writable");
  if(!is_aligned(array))
    throw py::value_error(std::string(argument) + " is not aligned (a view of a buffer at an odd offset)");
  return {array, view_of(array)};
}

/// The data of `object` when it is a writable contiguous (n,) float64 array (checked, ValueError naming
/// `argument`); nullptr for None.
double* output_values(const py::object& object, const char* argument, std::size_t n)
{
  if(object.is_none()) return nullptr;
  if(!py::isinstance<py::array>(object))
    throw py::value_error(std::string(argument) + " must be a numpy array of shape (" + std::to_string(n) +
                          ",) and dtype float64");
  auto array = py::reinterpret_borrow<py::array>(object);
  if(array.ndim() != 1 || std::size_t(array.shape(0)) != n)
    throw py::value_error(std::string(argument) + " must have shape (" + std::to_string(n) + ",), not " +
                          shape_of(array));
  if(!array.dtype().equal(py::dtype::of<double>()))
    throw py::value_error(std::string(argument) + " must have dtype float64, not " + dtype_name(array));
  if(!array.writeable()) throw py::value_error(std::string(argument) + " is not writable");
  if(n > 1 && array.strides(0) != py::ssize_t(sizeof(double)))
    throw py::value_error(std::string(argument) + " must be contiguous");
  if(!is_aligned(array))
    throw py::value_error(std::string(argument) + " is not aligned (a view of a buffer at an odd offset)");
  return static_cast<double*>(array.mutable_data());
}

/// Row i of a `Rows3` as a CGAL property map over indices: points, or vectors (normals, details).
template <typename Value>
struct Rows3_map
{
  using key_type = std::size_t;
  using value_type = Value;
  using reference = Value;
  using category = boost::read_write_property_map_tag;
  Rows3 rows;

  friend Value get(const Rows3_map& m, std::size_t i)
  {
    if(read_trace.on.load(std::memory_order_relaxed)) read_trace.note(&m.rows.at(i, 0), &m.rows.at(i, 2) + 1);
    return Value(m.rows.at(i, 0), m.rows.at(i, 1), m.rows.at(i, 2));
  }
  friend void put(const Rows3_map& m, std::size_t i, const Value& v)
  {
    m.rows.at(i, 0) = v.x();
    m.rows.at(i, 1) = v.y();
    m.rows.at(i, 2) = v.z();
  }
};

/// Element i of a 1-D array as a writable property map.
template <typename T>
struct Array_map
{
  using key_type = std::size_t;
  using value_type = T;
  using reference = T&;
  using category = boost::lvalue_property_map_tag;
  T* data;

  friend T& get(const Array_map& m, std::size_t i) { return m.data[i]; }
  friend void put(const Array_map& m, std::size_t i, const T& v) { m.data[i] = v; }
};

/// Point indices given as a 1-D array or sequence of integers, or as a boolean mask of all `n` points, each
/// checked against `n`.
std::vector<std::size_t> indices(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "a 1-D array of point indices or a boolean mask");
  const char kind = array.dtype().kind();
  if(array.ndim() != 1 || !(kind == 'i' || kind == 'u' || kind == 'b' || array.size() == 0))
    throw py::value_error(std::string(argument) + " must be a 1-D array of integer point indices or a boolean mask, not " +
                          (array.ndim() != 1 ? "shape " + shape_of(array) : "dtype " + dtype_name(array)));
  std::vector<std::size_t> out;
  if(kind == 'b') {
    if(std::size_t(array.size()) != n)
      throw py::value_error(std::string(argument) + ": a boolean mask needs one value per point (" + std::to_string(n) +
                            "), not " + std::to_string(array.size()));
    const auto mask = py::array_t<bool, py::array::forcecast | aligned_copy>::ensure(array);
    for(py::ssize_t m = 0; m < mask.size(); ++m)
      if(mask.at(m)) out.push_back(std::size_t(m));
    return out;
  }
  const auto values = py::array_t<long long, py::array::forcecast | aligned_copy>::ensure(array);
  out.resize(std::size_t(values.size()));
  for(py::ssize_t m = 0; m < values.size(); ++m) {
    const long long v = values.at(m);
    if(v < 0 || std::size_t(v) >= n)
      throw py::value_error(std::string(argument) + ": index " + std::to_string(v) + " is not a point index (" +
                            std::to_string(n) + " points)");
    out[std::size_t(m)] = std::size_t(v);
  }
  return out;
}

/// A 1-D array of `n` real numbers as float64 values.
std::vector<double> values_of(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "a 1-D array of numbers");
  const char kind = array.dtype().kind();
  if(array.ndim() != 1 || !(kind == 'f' || kind == 'i' || kind == 'u' || kind == 'b'))
    throw py::value_error(std::string(argument) + " must be a 1-D array of numbers, not " +
                          (array.ndim() != 1 ? "shape " + shape_of(array) : "dtype " + dtype_name(array)));
  if(std::size_t(array.size()) != n)
    throw py::value_error(std::string(argument) + " must have one value per point (" + std::to_string(n) + "), not " +
                          std::to_string(array.size()));
  const auto values = py::array_t<double, py::array::forcecast | py::array::c_style | aligned_copy>::ensure(array);
  return std::vector<double>(values.data(), values.data() + values.size());
}

/// An (n, 3) array of colours, integers in 0..255.
std::vector<point_detail::Color> colors_of(const py::handle& object, std::size_t n, const char* argument)
{
  const py::array array = as_array(object, argument, "an (n, 3) array of integers in 0..255");
  const char kind = array.dtype().kind();
  if(kind != 'i' && kind != 'u')
    throw py::value_error(std::string(argument) + " must hold integers in 0..255 (uint8), not dtype " + dtype_name(array));
  if(array.ndim() != 2 || array.shape(1) != 3 || std::size_t(array.shape(0)) != n)
    throw py::value_error(std::string(argument) + " must have shape (" + std::to_string(n) + ", 3), not " + shape_of(array));
  const auto values = py::array_t<long long, py::array::forcecast | py::array::c_style | aligned_copy>::ensure(array);
  std::vector<point_detail::Color> colors(n);
  for(std::size_t i = 0; i < n; ++i)
    for(int c = 0; c < 3; ++c) {
      const long long v = values.data()[3 * i + std::size_t(c)];
      if(v < 0 || v > 255)
        throw py::value_error(std::string(argument) + ": colour " + std::to_string(v) + " of point " + std::to_string(i) +
                              " is outside 0..255");
      colors[i][std::size_t(c)] = static_cast<unsigned char>(v);
    }
  return colors;
}

Index_range all_points(std::size_t n) { return boost::counting_range(std::size_t(0), n); }

/// Points and, unless None, normals as float64 arrays (kept alive here while the library reads them in place).
struct Point_input
{
  py::array points, normals;
  Rows3 point_rows, normal_rows;
  bool has_normals = false;

  Point_input(const py::handle& point_object, const py::handle& normal_object)
      : points(float64_rows3(point_object, "points")), point_rows(view_of(points))
  {
    if(normal_object.is_none()) return;
    normals = float64_rows3(normal_object, "normals");
    normal_rows = view_of(normals);
    has_normals = true;
    if(normal_rows.rows != point_rows.rows)
      throw py::value_error("normals must have as many rows as points (" + std::to_string(point_rows.rows) + "), not " +
                            std::to_string(normal_rows.rows));
  }

  std::size_t size() const { return std::size_t(point_rows.rows); }
};

/// The named parameters of `input`'s points and, when given, normals, given to `body(np)`.
template <typename Body>
auto with_maps(const Point_input& input, Body&& body)
{
  const auto np = CGAL::parameters::point_map(Rows3_map<Point>{input.point_rows});
  if(!input.has_normals) return body(np);
  return body(np.normal_map(Rows3_map<Vector>{input.normal_rows}));
}

} // namespace

#endif // CGAL_EXT_PYTHON_ARRAYS_H
