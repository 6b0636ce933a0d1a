// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "files.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <sstream>

namespace point_detail {
namespace fs = std::filesystem;

std::ifstream open_input(const fs::path& path, std::ios::openmode mode)
{
  std::error_code ec;
  if(!fs::exists(path, ec)) throw Cli_error("cannot read " + path.string() + ": no such file");
  if(!fs::is_regular_file(path, ec)) throw Cli_error("cannot read " + path.string() + ": not a regular file");
  std::ifstream in(path, mode);
  if(!in) throw Cli_error("cannot read " + path.string() + ": permission denied");
  return in;
}

void write_file(const fs::path& path, const std::string& bytes)
{
  std::ofstream out(path, std::ios::binary);
  errno = 0;
  out.write(bytes.data(), std::streamsize(bytes.size()));
  out.close();
  if(!out)
    throw Cli_error("cannot write " + path.string() + ": " +
                    (errno != 0 ? std::strerror(errno) : "disk full or not writable?"));
}

std::uint64_t file_bytes(const fs::path& path)
{
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  if(ec) throw Cli_error("cannot read " + path.string() + ": " + ec.message());
  return size;
}

bool header_words(std::string line, std::vector<std::string>& words)
{
  if(!line.empty() && line.back() == '\r') line.pop_back();
  words.clear();
  if(std::any_of(line.begin(), line.end(), [](unsigned char c) { return (c < 0x20 && c != '\t') || c == 0x7f; }))
    return false;
  std::istringstream in(line);
  for(std::string word; in >> word;) words.push_back(word);
  return true;
}

bool whole_number(const std::string& token, std::uint64_t& value)
{
  if(token.empty() || token.size() > 18 || token.find_first_not_of("0123456789") != std::string::npos) return false;
  value = std::stoull(token);
  return true;
}

std::string lower_extension(const fs::path& path)
{
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext.empty() ? ext : ext.substr(1);
}

namespace {

/// Available memory in bytes (MemAvailable of /proc/meminfo), or 0 when it cannot be read.
std::uint64_t available_memory()
{
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  std::string unit;
  while(meminfo >> key >> kib >> unit)
    if(key == "MemAvailable:") return kib * 1024;
  return 0;
}

std::string gibibytes(double bytes)
{
  std::ostringstream os;
  os.precision(bytes < 1024.0 * 1024 * 1024 * 10 ? 2 : 0);
  os << std::fixed << bytes / (1024.0 * 1024 * 1024) << " GiB";
  return os.str();
}

} // namespace

void check_memory_for(const fs::path& path, std::uint64_t points, std::uint64_t bytes_per_point)
{
  if(bytes_per_point == 0) return;
  const std::uint64_t available = available_memory();
  if(available > 0 && points > available / bytes_per_point)
    throw Cli_error("cannot read " + path.string() + ": it announces " + std::to_string(points) +
                    " points, which need about " + gibibytes(double(points) * bytes_per_point) +
                    " of memory; this machine has " + gibibytes(double(available)) + " available");
}

bool Buffered_bytes::read(unsigned char* out, std::size_t n)
{
  while(n > 0) {
    if(m_at == m_end && !refill()) return false;
    const std::size_t step = std::min(n, m_end - m_at);
    std::memcpy(out, m_buffer.data() + m_at, step);
    out += step;
    m_at += step;
    n -= step;
  }
  return true;
}

bool Buffered_bytes::skip(std::uint64_t n)
{
  while(n > 0) {
    if(m_at == m_end && !refill()) return false;
    const std::size_t step = std::size_t(std::min<std::uint64_t>(n, m_end - m_at));
    m_at += step;
    n -= step;
  }
  return true;
}

bool Buffered_bytes::refill()
{
  m_in.read(m_buffer.data(), std::streamsize(m_buffer.size()));
  m_at = 0;
  m_end = std::size_t(m_in.gcount());
  return m_end > 0;
}

} // namespace point_detail
