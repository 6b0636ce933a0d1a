// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// What a run of point-detail needs, whatever its subcommand: the process set-up, Ctrl-C, progress,
// whole-or-nothing output files, reports (errors and file access: the I/O layer's files.h).
#ifndef POINT_DETAIL_PROGRAM_BASICS_H
#define POINT_DETAIL_PROGRAM_BASICS_H

#include "files.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace point_detail {

/// Thrown when Ctrl-C or a callback stopped the run: nothing is written, exit code 130.
struct Cancelled : std::runtime_error
{
  Cancelled() : std::runtime_error("cancelled") {}
};

/// Re-executes the program, once, with
/// - glibc's malloc backed by transparent huge pages (GLIBC_TUNABLES glibc.malloc.hugetlb=1) unless that is
///   already set or POINT_DETAIL_HUGE_PAGES=0: every large array then costs one page fault per 2 MiB instead of
///   per 4 KiB, which on virtual machines, where page faults are expensive, halves the time of sparse
///   factorisations (doc/detail_scaling.md);
/// - OpenBLAS's AVX2 kernels (OPENBLAS_CORETYPE=Haswell) when OpenBLAS, CHOLMOD's BLAS, picked kernels
///   older than AVX2 on a CPU that has AVX2 and FMA (`openblas_core_predates_avx2`), unless OPENBLAS_CORETYPE
///   is set or POINT_DETAIL_OPENBLAS_CORE=0. OpenBLAS falls back to its SSE3 kernels (Prescott) on a CPU whose
///   model it does not know, as a virtual machine's generic one; they take twice as long to factor
///   (doc/editing_at_scale.md, "Editing's factorisation").
/// Returns only when the program runs as it is (nothing to change, disabled, or the exec failed).
void tune_process_environment(char** argv);
/// "transparent huge pages" or "4 KiB pages", as the running process's malloc was set up (for reports).
std::string malloc_pages();
/// The name of the OpenBLAS kernels the process runs ("Haswell", "Prescott", ...), empty when BLAS is not OpenBLAS.
std::string blas_kernels();
/// "OpenBLAS, Haswell kernels" or "not OpenBLAS" (for reports).
std::string blas_description();
/// Whether `core`, an OpenBLAS core name (`openblas_get_corename()`), names kernels for a CPU older than
/// AVX2 and FMA.
bool openblas_core_predates_avx2(const std::string& core);

/// How long after Ctrl-C a run that has not reached a progress report is ended anyway (its temporaries removed,
/// exit status 130).
constexpr std::chrono::milliseconds cancel_grace_period{1000};

/// Installs the SIGINT handler that turns Ctrl-C into a cancellation at the next progress report, and the
/// watchdog that ends the run `cancel_grace_period` later if it is still computing.
void install_interrupt_handler();
bool interrupted();

/// Progress of one named stage on stderr: a bar on a terminal, a line per 10 % otherwise.
class Progress_printer
{
public:
  explicit Progress_printer(bool quiet) : m_quiet(quiet) {}
  /// A callback for the library (`false` after Ctrl-C).
  std::function<bool(double)> stage(const std::string& name);
  void finish();

private:
  bool m_quiet;
  std::string m_name;
  int m_last = -1;
  bool m_open = false;
};

/// Collects output files as temporaries next to their destinations and renames them all at the end, so a
/// failed or cancelled run leaves no partial file. Refuses to write over any input.
class Output_files
{
public:
  explicit Output_files(std::vector<std::filesystem::path> inputs) : m_inputs(std::move(inputs)) {}
  ~Output_files();
  /// Checks `destination` (not an input, directory exists) and returns the temporary path to write to.
  std::filesystem::path add(const std::filesystem::path& destination);
  /// Renames every temporary to its destination.
  void commit();

private:
  std::vector<std::filesystem::path> m_inputs;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> m_files; // temporary, destination
};

/// Stage timings and counts for `--report`.
class Report
{
public:
  explicit Report(std::string command);
  /// Times `body` under `stage` and returns its result.
  template <typename F>
  auto time(const std::string& stage, F&& body)
  {
    const auto start = std::chrono::steady_clock::now();
    if constexpr(std::is_void_v<decltype(body())>) {
      body();
      record(stage, start);
    } else {
      auto result = body();
      record(stage, start);
      return result;
    }
  }
  nlohmann::json& data() { return m_json; }
  std::string dump() const { return m_json.dump(2) + "\n"; }

private:
  void record(const std::string& stage, std::chrono::steady_clock::time_point start);
  nlohmann::json m_json;
};

} // namespace point_detail

#endif
