// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#include "program_basics.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <mutex>
#include <system_error>
#include <thread>
#include <dlfcn.h>
#include <unistd.h>

namespace point_detail {

namespace {
using Corename_function = char* (*)();

/// OpenBLAS's `openblas_get_corename`, looked up rather than linked: CHOLMOD reaches BLAS through Debian's
/// libblas.so.3 alternative, which need not be OpenBLAS.
Corename_function openblas_corename() { return reinterpret_cast<Corename_function>(dlsym(RTLD_DEFAULT, "openblas_get_corename")); }

/// Whether the environment variable `name` is "0", the project's way to turn one of its own settings off.
bool turned_off(const char* name)
{
  const char* value = std::getenv(name);
  return value && std::string(value) == "0";
}

bool cpu_has_avx2_and_fma()
{
#if defined(__x86_64__) || defined(__i386__)
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}
} // namespace

bool openblas_core_predates_avx2(const std::string& core)
{
  // openblas_get_corename()'s names of the kernels for x86 CPUs without AVX2 and FMA (OpenBLAS 0.3, DYNAMIC_ARCH).
  static const char* const older[] = {"Katmai", "Coppermine", "Northwood", "Prescott", "Banias", "Core2", "Penryn", "Dunnington",
                                      "Nehalem", "Atom", "Nano", "Sandybridge", "Athlon", "Opteron", "Opteron_SSE3", "Barcelona",
                                      "Bobcat", "Bulldozer", "Piledriver", "Steamroller"};
  return std::find(std::begin(older), std::end(older), core) != std::end(older);
}

std::string blas_kernels()
{
  const Corename_function corename = openblas_corename();
  const char* core = corename ? corename() : nullptr;
  return core ? core : "";
}

std::string blas_description()
{
  const std::string core = blas_kernels();
  return core.empty() ? "not OpenBLAS" : "OpenBLAS, " + core + " kernels";
}

void tune_process_environment(char** argv)
{
  const char* current = std::getenv("GLIBC_TUNABLES");
  const std::string tunables = current ? current : "";
  const bool set_huge_pages = tunables.find("glibc.malloc.hugetlb") == std::string::npos && !turned_off("POINT_DETAIL_HUGE_PAGES");
  const bool set_blas_core = !std::getenv("OPENBLAS_CORETYPE") && !turned_off("POINT_DETAIL_OPENBLAS_CORE") &&
                             openblas_core_predates_avx2(blas_kernels()) && cpu_has_avx2_and_fma();
  if(!set_huge_pages && !set_blas_core) return;
  if(set_huge_pages) setenv("GLIBC_TUNABLES", ((tunables.empty() ? "" : tunables + ":") + "glibc.malloc.hugetlb=1").c_str(), 1);
  if(set_blas_core) setenv("OPENBLAS_CORETYPE", "Haswell", 1);
  execv("/proc/self/exe", argv);
  // The exec failed: run as we are, with the environment as it was (setenv may have reused `current`).
  if(current) setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
  else unsetenv("GLIBC_TUNABLES");
  if(set_blas_core) unsetenv("OPENBLAS_CORETYPE");
}

std::string malloc_pages()
{
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return tunables && std::string(tunables).find("glibc.malloc.hugetlb=1") != std::string::npos ? "transparent huge pages"
                                                                                                 : "4 KiB pages";
}

namespace fs = std::filesystem;

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

/// The temporaries of every Output_files, for the watchdog. Never destroyed: the watchdog may outlive main().
struct Pending_outputs
{
  std::mutex mutex;
  std::vector<fs::path> temporaries;
  bool committing = false;
};

Pending_outputs& pending_outputs()
{
  static Pending_outputs* pending = new Pending_outputs;
  return *pending;
}

/// Ctrl-C cancels at the next progress report; a step that reports none (a sparse factorisation of a large
/// region) would keep the user waiting for it. A second after the interrupt, if the run has not ended, the
/// watchdog removes the temporaries and ends the process with the cancellation's status, unless the outputs
/// are being renamed into place (then the run ends on its own, whole).
void watch_for_interrupt()
{
  using namespace std::chrono_literals;
  while(!g_interrupted) std::this_thread::sleep_for(50ms);
  std::this_thread::sleep_for(cancel_grace_period);
  Pending_outputs& pending = pending_outputs();
  std::lock_guard<std::mutex> lock(pending.mutex);
  if(pending.committing) return;
  std::error_code ec;
  for(const fs::path& temporary : pending.temporaries) fs::remove(temporary, ec);
  std::fputs("\npoint-detail: cancelled; nothing written\n", stderr);
  std::_Exit(130);
}
} // namespace

void install_interrupt_handler()
{
  std::signal(SIGINT, on_sigint);
  std::thread(watch_for_interrupt).detach();
}

bool interrupted() { return g_interrupted; }

std::function<bool(double)> Progress_printer::stage(const std::string& name)
{
  finish();
  m_name = name;
  m_last = -1;
  return [this](double fraction) {
    if(interrupted()) return false;
    if(m_quiet) return true;
    const bool tty = isatty(fileno(stderr));
    const int percent = int(fraction * 100.0 + 1e-9);
    if(tty) {
      if(percent == m_last) return true;
      const int width = 30, filled = percent * width / 100;
      std::fprintf(stderr, "\r%-12s [%s%s] %3d%%", m_name.c_str(), std::string(std::size_t(filled), '#').c_str(),
                   std::string(std::size_t(width - filled), ' ').c_str(), percent);
      m_open = true;
    } else {
      if(percent / 10 == m_last / 10 && m_last >= 0) return true;
      std::fprintf(stderr, "%s: %d%%\n", m_name.c_str(), percent / 10 * 10);
    }
    m_last = percent;
    return true;
  };
}

void Progress_printer::finish()
{
  if(m_open) std::fputc('\n', stderr);
  m_open = false;
}

Output_files::~Output_files()
{
  std::error_code ec;
  Pending_outputs& pending = pending_outputs();
  std::lock_guard<std::mutex> lock(pending.mutex);
  for(const auto& f : m_files) { // left over only when commit() was not reached
    fs::remove(f.first, ec);
    pending.temporaries.erase(std::remove(pending.temporaries.begin(), pending.temporaries.end(), f.first),
                              pending.temporaries.end());
  }
}

fs::path Output_files::add(const fs::path& destination)
{
  std::error_code ec;
  for(const fs::path& input : m_inputs)
    if(fs::exists(destination, ec) && fs::equivalent(input, destination, ec))
      throw Cli_error("output " + destination.string() + " is the input file; choose another output name");
  for(const auto& f : m_files)
    if(fs::weakly_canonical(f.second, ec) == fs::weakly_canonical(destination, ec))
      throw Cli_error("output " + destination.string() + " is named twice");
  const fs::path dir = destination.has_parent_path() ? destination.parent_path() : fs::path(".");
  if(!fs::exists(dir, ec))
    throw Cli_error("cannot write " + destination.string() + ": directory " + dir.string() + " does not exist");
  if(!fs::is_directory(dir, ec))
    throw Cli_error("cannot write " + destination.string() + ": " + dir.string() + " is not a directory");
  if(fs::is_directory(destination, ec))
    throw Cli_error("cannot write " + destination.string() + ": it is a directory");
  std::random_device rd;
  const fs::path temporary = dir / ("." + destination.filename().string() + "." + std::to_string(rd()) + ".tmp");
  // Created now, so an unwritable directory fails before the work, not after it.
  if(!std::ofstream(temporary, std::ios::binary))
    throw Cli_error("cannot write " + destination.string() + ": directory " + dir.string() + " is not writable (" +
                    std::strerror(errno) + ")");
  m_files.emplace_back(temporary, destination);
  Pending_outputs& pending = pending_outputs();
  std::lock_guard<std::mutex> lock(pending.mutex);
  pending.temporaries.push_back(temporary);
  return temporary;
}

void Output_files::commit()
{
  Pending_outputs& pending = pending_outputs();
  std::lock_guard<std::mutex> lock(pending.mutex);
  if(interrupted()) throw Cancelled();
  pending.committing = true;
  for(const auto& f : m_files) {
    std::error_code ec;
    fs::rename(f.first, f.second, ec);
    if(ec) throw Cli_error("cannot write " + f.second.string() + ": " + ec.message());
    pending.temporaries.erase(std::remove(pending.temporaries.begin(), pending.temporaries.end(), f.first),
                              pending.temporaries.end());
  }
  m_files.clear();
}

Report::Report(std::string command)
{
  m_json["command"] = std::move(command);
  m_json["timings_s"] = nlohmann::json::object();
}

void Report::record(const std::string& stage, std::chrono::steady_clock::time_point start)
{
  m_json["timings_s"][stage] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace point_detail
