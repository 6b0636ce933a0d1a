// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// What every reader and writer of the I/O layer shares: the error a user can fix, opening and writing files,
// the memory check made before a file's announced points are allocated, and buffered sequential reading.
#ifndef POINT_DETAIL_FILES_H
#define POINT_DETAIL_FILES_H

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace point_detail {

/// A problem the user can fix (bad file, bad option): printed as one line, exit code 1.
struct Cli_error : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Opens an input file for reading, or throws Cli_error: missing, not a regular file (a device such as
/// /dev/zero would never end), or unreadable.
std::ifstream open_input(const std::filesystem::path& path, std::ios::openmode mode = std::ios::in);

/// Writes `bytes` to `path` or throws Cli_error.
void write_file(const std::filesystem::path& path, const std::string& bytes);

/// The size of a regular file in bytes (Cli_error if it cannot be read).
std::uint64_t file_bytes(const std::filesystem::path& path);

/// Fails early, before any reader allocates, for a file that announces more points than this machine's memory
/// can process at `bytes_per_point` (0: no check, for a file that is mapped rather than read).
void check_memory_for(const std::filesystem::path& path, std::uint64_t points, std::uint64_t bytes_per_point);

/// The words of a line of a text header (PLY, PCD), its '\r' dropped; false when the line holds a control
/// character (a NUL byte in a name would read differently in each reader).
bool header_words(std::string line, std::vector<std::string>& words);

/// `token` as a count: decimal digits only, at most 18 of them; false otherwise.
bool whole_number(const std::string& token, std::uint64_t& value);

/// The extension of `path` in lower case, without its dot.
std::string lower_extension(const std::filesystem::path& path);

/// Sequential reads and skips over a stream through a large buffer: a binary walk visits every record, and an
/// istream call per field would cost more than the reading it guards.
class Buffered_bytes
{
public:
  explicit Buffered_bytes(std::istream& in) : m_in(in), m_buffer(std::size_t(1) << 20) {}

  /// Reads n bytes into `out`; false if the stream ends first.
  bool read(unsigned char* out, std::size_t n);
  /// Skips n bytes; false if the stream ends first.
  bool skip(std::uint64_t n);

private:
  bool refill();

  std::istream& m_in;
  std::vector<char> m_buffer;
  std::size_t m_at = 0, m_end = 0;
};

} // namespace point_detail

#endif
