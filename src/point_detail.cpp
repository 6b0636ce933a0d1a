// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
// point-detail: high-frequency geometric details of point-sampled surfaces from the command line. Each
// subcommand lives in a file of its own (src/*_command.cpp); this one parses, runs the chosen one and turns
// errors into exit statuses.
#include "commands.h"

#include <CGAL_ext/exceptions.h>

#include <CLI/CLI.hpp>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <csignal>
#include <cstdio>
#include <memory>
#include <new>

using namespace point_detail;

int main(int argc, char** argv)
{
  tune_process_environment(argv);
  CLI::App app{"point-detail: high-frequency geometric details of point-sampled surfaces (Miao et al. 2007)"};
  app.require_subcommand(1);
  app.fallthrough(); // the global options are taken after the subcommand too, as people type them
  app.set_version_flag("--version", "point-detail (CGAL_ext); malloc: " + malloc_pages() + "; BLAS: " + blas_description(),
                       "the program and the environment it runs in (memory pages, BLAS kernels)");
  Common_options common;
  app.add_option("--threads", common.threads, "worker threads (0: all cores)")->check(CLI::NonNegativeNumber);
  app.add_flag("-q,--quiet", common.quiet, "no progress on stderr");
  app.add_flag("--cloudcompare-fields", common.cloudcompare_fields,
               "name each scalar field of the PLY files written scalar_NAME, as CloudCompare's command line loads "
               "them (it shows NAME)");

  std::vector<Subcommand> subcommands{add_details_command(app, common)};
  for(Subcommand& s : add_manipulate_commands(app, common)) subcommands.push_back(std::move(s));
  for(auto add : {add_curvature_command, add_simplify_command, add_edit_command, add_upsample_command,
                  add_render_command, add_demo_command})
    subcommands.push_back(add(app, common));

  CLI11_PARSE(app, argc, argv);
  install_interrupt_handler();
  // A write past the file-size limit (ulimit -f, the nearest thing to a full disk) then fails with EFBIG, which
  // write_file reports, instead of the signal killing the program and leaving its temporary file behind.
  std::signal(SIGXFSZ, SIG_IGN);
#ifdef CGAL_LINKED_WITH_TBB
  std::unique_ptr<tbb::global_control> threads;
  if(common.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, std::size_t(common.threads));
#endif
  try {
    for(const Subcommand& s : subcommands)
      if(*s.app) s.run();
  } catch(const Cancelled&) {
    std::fprintf(stderr, "\npoint-detail: cancelled; nothing written\n");
    return 130;
  } catch(const Cli_error& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 1;
  } catch(const CGAL_ext::Invalid_input& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 1;
  } catch(const CGAL_ext::Numerical_failure& e) {
    std::fprintf(stderr, "point-detail: error: %s\n", e.what());
    return 3;
  } catch(const std::bad_alloc&) {
    std::fprintf(stderr, "point-detail: error: out of memory; free memory, raise the process's memory limit or "
                         "work on a smaller region\n");
    return 3;
  } catch(const std::exception& e) {
    std::fprintf(stderr, "point-detail: failed: %s\n", e.what());
    return 3;
  }
  return 0;
}
