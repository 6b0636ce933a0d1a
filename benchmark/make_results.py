#!/usr/bin/python3
"""Gathers the benchmark programs' CSV files into one RESULTS.md, one results.csv and the scaling plot.

Usage: benchmark/make_results.py OUT_DIR BUILD_DIR
       benchmark/make_results.py --merge OUT_DIR     (results.csv only, after one stage was run again)
OUT_DIR holds the *_results.csv files of bench_editing, bench_upsampling, bench_simplification, bench_curvature,
bench_scaling, bench_details and measure_edit_memory.sh; BUILD_DIR is the CMake build they came from (for the
compiler and its flags). Writes OUT_DIR/RESULTS.md, OUT_DIR/results.csv and OUT_DIR/scaling.png.
results.csv holds every stage's figures, one per line (source, section, row, column, value): the manual and the
README quote them by that key (scripts/check_quoted_figures.py).
"""
import csv
import datetime
import os
import platform
import re
import subprocess
import sys


# bench_editing writes one CSV with a section per table; these are each section's columns after the first.
EDITING_COLUMNS = {
    "table1": ["model", "order", "points", "ssps", "roi_ssps", "preprocess_s", "editing_ssps_s", "editing_ssps_min_s",
               "editing_ssps_max_s", "diffusion_s", "diffusion_min_s", "diffusion_max_s", "drag_median_s", "drag_min_s",
               "drag_max_s"],
    "scaling": ["model", "order", "solver", "points", "ssps", "roi_ssps", "preprocess_s", "editing_ssps_s",
                "drag_median_s", "drag_min_s", "drag_max_s", "cg_iterations"],
    "large_system": ["model", "points", "ssp_target", "ssps", "unknowns", "normal_nonzeros", "assembly_s", "factor_s",
                     "factor_min_s", "factor_max_s"],
    "arap": ["model", "method", "preprocess_s", "deform_s", "hausdorff_to_sre_arap", "detail_change",
             "handle_error", "ssps", "stretch_p99", "hausdorff_to_sre_arap_1000_iterations", "per_drag_s", "clustering_s",
             "factor_s", "stretch_max"],
    "cactus": ["turn_degrees", "method", "hausdorff_to_sre_arap", "hausdorff_to_converged_sre_arap",
               "hausdorff_to_converged_original_arap"],
    "diffusion": ["model", "encoding", "detail_change", "largest_stretch", "diffusion_s"],
    "ssp_quality": ["model", "sample_points", "ssps", "drag_median_s", "hausdorff_to_every_point_result"],
}

# The paper's Table 1 (Pentium 4, 2.0 GHz): points, SSPs, ROI SSPs, then editing SSPs and diffusion seconds
# for the linear, quadric and cubic details (None: not given).
PAPER_TABLE1 = {
    "horse": (48484, 3287, 687, [(0.1014, 0.3223), (0.1897, 0.3239), (1.1658, 0.3247)]),
    "dog": (95063, 5275, 2135, [(0.3180, 0.7476), (0.9469, 0.7497), (9.4520, 0.7499)]),
    "tentacle": (44383, 3339, 3122, [(1.6070, 0.8278), (1.9777, 0.8338), (20.7778, 0.8423)]),
    "dinosaur": (56194, 5954, 5584, [(2.5838, 1.1815), (4.8977, 1.5482), (None, None)]),
}


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_editing(path):
    sections = {name: [] for name in EDITING_COLUMNS}
    if not os.path.exists(path):
        return sections
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    for row in rows[1:]:
        columns = EDITING_COLUMNS.get(row[0])
        if columns is None or len(row) - 1 != len(columns):
            sys.exit(f"make_results.py: {path}: unexpected row {row}")
        sections[row[0]].append(dict(zip(columns, row[1:])))
    return sections


def command_output(args):
    try:
        return subprocess.run(args, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def machine_facts(build_dir, threads):
    cpu = ""
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    cache = {}
    cache_file = os.path.join(build_dir, "CMakeCache.txt")
    if os.path.exists(cache_file):
        with open(cache_file) as f:
            for line in f:
                m = re.match(r"([A-Za-z_]+):[A-Z]+=(.*)", line.strip())
                if m:
                    cache[m.group(1)] = m.group(2)
    compiler = cache.get("CMAKE_CXX_COMPILER", "c++")
    version = command_output([compiler, "--version"]).splitlines()
    build_type = cache.get("CMAKE_BUILD_TYPE", "")
    flags = " ".join(x for x in [cache.get("CMAKE_CXX_FLAGS", ""),
                                 cache.get("CMAKE_CXX_FLAGS_" + build_type.upper(), "")] if x)
    packages = []
    for p in ["libcgal-dev", "libeigen3-dev", "libboost-dev", "libtbb-dev", "libsuitesparse-dev", "libopenblas-dev"]:
        v = command_output(["dpkg-query", "-W", "-f=${Version}", p])
        packages.append(f"{p} {v or '(not installed)'}")
    with open("/proc/meminfo") as f:
        memory = next((line.split()[1] for line in f if line.startswith("MemTotal")), "0")
    return [
        ("CPU", f"{cpu}, {os.cpu_count()} cores, {int(memory) / 1024 / 1024:.0f} GiB"),
        ("threads used", threads),
        ("system", f"{platform.system()} {platform.release()}"),
        ("compiler", version[0] if version else compiler),
        ("build", f"{build_type}, flags `{flags}`"),
        ("libraries", ", ".join(packages)),
        ("date", datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")),
    ]


def number(value, digits=3):
    return f"{float(value):.{digits}f}"


def ratio(a, b):
    return f"{float(a) / float(b):.2g}x" if float(b) > 0 else ""


def table(out, header, rows):
    out.append("| " + " | ".join(header) + " |")
    out.append("|" + "|".join("---" if i < 2 else "---:" for i in range(len(header))) + "|")
    for r in rows:
        out.append("| " + " | ".join(str(x) for x in r) + " |")
    out.append("")


def table1_section(out, editing):
    out.append("## 1. The paper's Table 1 on our models\n")
    out.append("Editing the SSPs (operator, normal matrix, factorisation, first solve) and diffusing to every point, "
               "in seconds, for the linear, quadric and cubic details; per drag: one deform() and diffuse() of the "
               "quadric edit. The paper's rows (Pentium 4, 2.0 GHz, one thread) follow ours; the tentacle is generated "
               "at the paper's size (`CGAL_ext::shapes::bumpy_tube`).\n")
    by_model = {}
    for r in editing["table1"]:
        by_model.setdefault(r["model"], {})[r["order"]] = r
    rows = []
    for model, orders in by_model.items():
        if not all(o in orders for o in ("linear", "quadric", "cubic")):
            continue
        q = orders["quadric"]
        rows.append([model, q["points"], q["ssps"], q["roi_ssps"]] +
                    [f"{number(orders[o]['editing_ssps_s'], 4)} ({number(orders[o]['editing_ssps_min_s'], 4)}-"
                     f"{number(orders[o]['editing_ssps_max_s'], 4)}) / {number(orders[o]['diffusion_s'], 4)}"
                     for o in ("linear", "quadric", "cubic")] +
                    [f"{1e3 * float(q['drag_median_s']):.1f} ({1e3 * float(q['drag_min_s']):.1f}-"
                     f"{1e3 * float(q['drag_max_s']):.1f})"])
    for model, (points, ssps, roi, times) in PAPER_TABLE1.items():
        cells = [f"{e} / {d}" if e is not None else "not given" for e, d in times]
        rows.append([f"*paper: {model}*", points, ssps, roi] + cells + [""])
    table(out, ["model", "points", "SSPs", "ROI SSPs", "linear s: SSPs (min-max) / diffusion", "quadric s", "cubic s",
                "per drag ms (min-max)"], rows)
    tentacle = by_model.get("tentacle (generated)")
    if tentacle:
        speedups = [ratio(PAPER_TABLE1["tentacle"][3][i][0], tentacle[o]["editing_ssps_s"])
                    for i, o in enumerate(("linear", "quadric", "cubic"))]
        out.append(f"Tentacle, editing the SSPs: {' / '.join(speedups)} faster than the paper's figures (linear / "
                   "quadric / cubic); the paper ran one Pentium 4 core at 2.0 GHz, the machine here is described above.\n")


def peers_section(out, editing, simplification, upsampling, curvature, accuracy):
    out.append("## 2. Each stage against its CGAL peer, in the same run\n")
    rows = []
    for model in dict.fromkeys(r["model"] for r in simplification):
        ours = [r for r in simplification if r["model"] == model and r["mode"] == "parallel"
                and r["stage"].startswith("compute_simplification_sample_points")]
        theirs = [r for r in simplification if r["model"] == model and r["mode"] == "parallel"
                  and r["stage"].startswith("CGAL hierarchy_simplify_point_set")]
        if ours and theirs:
            o, t = ours[0], theirs[0]
            rows.append(["SSPs (7D mean shift + clustering) vs `CGAL::hierarchy_simplify_point_set` (size 50)", model,
                         o["points"], f"{number(o['median_s'])} ({o['count']} SSPs)",
                         f"{number(t['median_s'])} ({t['count']} clusters)", ratio(o["median_s"], t["median_s"])])
    for model in dict.fromkeys(r["model"] for r in curvature):
        ours = [r for r in curvature if r["model"] == model and r["mode"] == "parallel"
                and r["method"] == "closed_form" and r["k"] == "15"]
        monge = [r for r in curvature if r["model"] == model and r["mode"] == "parallel"
                 and r["method"] == "monge_jet_fitting"]
        if ours and monge:
            o, t = ours[0], monge[0]
            rows.append(["mean curvature: closed-form fit vs CGAL's `Monge_via_jet_fitting` (both k 15)", model,
                         o["points"], number(o["median_s"]), number(t["median_s"]), ratio(o["median_s"], t["median_s"])])
    # The same two on analytic shapes, each time with its error against the exact curvature.
    for shape in dict.fromkeys(r["shape"] for r in accuracy):
        ours = [r for r in accuracy if r["shape"] == shape and r["method"].startswith("CGAL_ext")]
        theirs = [r for r in accuracy if r["shape"] == shape and r["method"].startswith("CGAL Monge")]
        if ours and theirs:
            o, t = ours[0], theirs[0]
            rows.append(["mean curvature, time (median relative error): closed form vs CGAL's `Monge_via_jet_fitting` (k 15)",
                         shape, o["points"], f"{number(o['median_s'])} ({float(o['median_relative_error']):.2e})",
                         f"{number(t['median_s'])} ({float(t['median_relative_error']):.2e})", ratio(o["median_s"], t["median_s"])])
    def farthest(r):
        # Beside it, the same where the reference's triangle is short enough to follow the edit.
        return (f"{number(r['largest_distance_of_new_h'], 2)} h; "
                f"{number(r['largest_distance_of_new_by_short_triangles_h'], 2)} h by triangles < 4 h")

    for model in dict.fromkeys(r["model"] for r in upsampling):
        ours = [r for r in upsampling if r["model"] == model and r["method"] == "ours (upsample_point_set)"]
        theirs = [r for r in upsampling if r["model"] == model and r["method"].startswith("CGAL edge_aware")]
        if ours and theirs:
            o, t = ours[0], theirs[0]
            rows.append(["up-sampling a stretched edit vs `CGAL::edge_aware_upsample_point_set` (same output size)",
                         model, o["points"],
                         f"{number(o['median_s'])} (+{o['inserted']}, covering {number(o['covering_radius_after_h'], 2)} h, "
                         f"farthest new {farthest(o)})",
                         f"{number(t['median_s'])} (covering {number(t['covering_radius_after_h'], 2)} h, farthest new "
                         f"{farthest(t)})", ratio(o["median_s"], t["median_s"])])
    points_of = {r["model"]: r["points"] for r in editing["table1"]}
    for model in dict.fromkeys(r["model"] for r in editing["arap"]):
        group = [r for r in editing["arap"] if r["model"] == model]
        sre = [r for r in group if r["method"].startswith("CGAL SRE_ARAP")]
        for method in ("ours, propagated (quadric)", "ours, ARAP (3 iterations)"):
            ours = [r for r in group if r["method"].startswith(method)]
            if sre and ours:
                o, t = ours[0], sre[0]
                vertices = re.search(r"\((\d+) vertices\)", model)
                rows.append([f"editing: {method}, one drag (deform + diffuse) vs `CGAL::Surface_mesh_deformation` "
                             "SRE_ARAP, 5 iterations (deform)", model,
                             vertices.group(1) if vertices else points_of.get(model, ""),
                             f"{number(o['deform_s'], 4)} (preprocess {number(o['preprocess_s'])})",
                             f"{number(t['deform_s'], 4)} (preprocess {number(t['preprocess_s'])})",
                             ratio(o["deform_s"], t["deform_s"])])
    table(out, ["stage", "model", "points", "ours s", "CGAL s", "ours / CGAL time"], rows)

    out.append("Quality of each edit beside CGAL's mesh ARAP (same mesh, region, control vertices and targets): "
               "ours per drag (median of every run's 20 drags through the edit), Hausdorff distance of the result to SRE_ARAP's, the rotation-compensated change of the region's own "
               "quadric details (relative to their size), the stretch of the region's kNN edges (99th percentile / largest) "
               "and the largest distance of a handle point from its target; distances relative to the bounding diagonal.\n")
    rows = [[r["model"], r["method"], number(r["preprocess_s"]), number(r["deform_s"], 4),
             f"{1e3 * float(r['per_drag_s']):.1f}" if r.get("per_drag_s") else "",
             "" if r["method"].startswith("CGAL SRE") else f"{100 * float(r['hausdorff_to_sre_arap']):.2f} %",
             number(r["detail_change"]), f"{number(r['stretch_p99'])} / {number(r['stretch_max'])}",
             f"{float(r['handle_error']):.1e}"] for r in editing["arap"]]
    table(out, ["model", "method", "preprocess s", "deform s", "per drag ms (median)", "Hausdorff to SRE_ARAP",
                "detail change", "kNN edge stretch", "handle error"], rows)


def scaling_section(out, editing, memory, plot_file):
    out.append("## 3. Scaling: samplings of the armadillo surface\n")
    out.append("Quadric details, Cholesky; the same edit scaled with the model (region 40 % of the diagonal around "
               "the point farthest along +x). Peak memory: a whole `point-detail edit` run (read, preprocess, one edit, "
               "diffuse, write) measured by `/usr/bin/time -v` (`benchmark/measure_edit_memory.sh`); target at most "
               "1 KiB per point.\n")
    memory_by_points = {r["points"]: r for r in memory}
    rows, sizes, preprocess, drag = [], [], [], []
    for r in editing["scaling"]:
        if r["order"] != "quadric" or r["solver"] != "cholesky":
            continue
        m = memory_by_points.get(r["points"])
        rows.append([r["model"], r["points"], r["ssps"], r["roi_ssps"], number(r["preprocess_s"]),
                     f"{1e3 * float(r['drag_median_s']):.1f} ({1e3 * float(r['drag_min_s']):.1f}-"
                     f"{1e3 * float(r['drag_max_s']):.1f})",
                     f"{float(m['peak_rss_mib']):.0f} MiB" if m else "", f"{float(m['bytes_per_point']):.0f} B" if m else "",
                     ("met" if float(m["bytes_per_point"]) <= 1024 else "**missed**") if m else ""])
        sizes.append(int(r["points"]))
        preprocess.append(float(r["preprocess_s"]))
        drag.append(float(r["drag_median_s"]))
    table(out, ["sampling", "points", "SSPs", "ROI SSPs", "preprocess s", "per drag ms (min-max)", "peak memory (whole edit)",
                "per point", "<= 1 KiB"], rows)
    if sizes:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5.5, 3.8), dpi=100)
        ax.loglog(sizes, preprocess, "o-", label="preprocess (SSPs, factorisation)")
        ax.loglog(sizes, drag, "s-", label="per drag (deform + diffuse)")
        whole = [(int(r["points"]), float(r["wall_s"])) for r in memory]
        if whole:
            ax.loglog([w[0] for w in whole], [w[1] for w in whole], "^-", label="whole edit run (with IO)")
        ax.set_xlabel("points")
        ax.set_ylabel("seconds")
        ax.set_title("Detail-preserving editing, armadillo samplings")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(plot_file)
        plt.close(fig)
        out.append(f"![time against size, log axes]({os.path.basename(plot_file)})\n")


def solver_section(out, editing):
    out.append("## 4. Cholesky against conjugate gradients, each order and size\n")
    out.append("Editing the SSPs: Cholesky assembles, factors and back-substitutes once; CG (Jacobi, matrix-free, "
               "the paper's method) solves iteratively, and again at every drag.\n")
    by_key = {}
    for r in editing["scaling"]:
        by_key.setdefault((r["model"], r["order"]), {})[r["solver"]] = r
    rows = []
    for (model, order), s in by_key.items():
        c = s.get("cholesky")
        if c is None:
            continue
        if "cg" in s:
            g = s["cg"]
            rows.append([model, order, c["roi_ssps"], number(c["editing_ssps_s"], 4), number(g["editing_ssps_s"], 4),
                         ratio(g["editing_ssps_s"], c["editing_ssps_s"]), number(1e3 * float(c["drag_median_s"]), 1),
                         number(1e3 * float(g["drag_median_s"]), 1), g["cg_iterations"]])
        elif "cg_not_converged" in s:
            g = s["cg_not_converged"]
            rows.append([model, order, c["roi_ssps"], number(c["editing_ssps_s"], 4),
                         f"not converged ({number(g['editing_ssps_s'], 1)} s to give up)", "",
                         number(1e3 * float(c["drag_median_s"]), 1), "", f">= {g['cg_iterations']}"])
    table(out, ["sampling", "order", "ROI SSPs", "Cholesky s", "CG s", "CG / Cholesky", "per drag ms, Cholesky",
                "per drag ms, CG", "CG iterations"], rows)


def memory_section(out, details, simplification, curvature):
    out.append("## 5. Peak memory per stage, on the largest sampling\n")
    out.append("The benchmark process's peak resident memory (`getrusage`) after each stage of its parallel run; it only "
               "grows, so a stage's figure covers the stages before it in the same program (the sampling itself included). "
               "Whole `point-detail edit` runs are in section 3.\n")
    rows = []
    for program, source, stage_key in [("bench_details", details, "stage"), ("bench_simplification", simplification, "stage"),
                                       ("bench_curvature", curvature, "method")]:
        largest = max((int(r["points"]) for r in source), default=0)
        for r in source:
            if int(r["points"]) == largest and r["mode"] == "parallel" and not r[stage_key].startswith("threshold sweep"):
                mib = float(r["peak_rss_mib"])
                stage = r[stage_key] + (f" (k {r['k']})" if "k" in r else "")
                rows.append([program, stage, r["points"], f"{mib:.0f} MiB", f"{mib * 1048576 / float(r['points']):.0f} B"])
    table(out, ["program", "stage", "points", "peak so far", "per point"], rows)


# The stages whose CSV files results.csv merges, beside bench_editing's sections.
STAGE_FILES = [("bench_simplification", "simplification_results.csv"), ("bench_upsampling", "upsampling_results.csv"),
               ("bench_curvature", "curvature_results.csv"), ("bench_curvature_accuracy", "curvature_accuracy.csv"),
               ("bench_normals", "normals_results.csv"), ("measure_edit_memory", "memory_results.csv"),
               ("measure_raw_scan", "raw_scan_results.csv"), ("bench_scaling", "scaling_results.csv"),
               ("bench_details", "details_results.csv"), ("bench_python", "python_results.csv"),
               ("bench_studio", "studio_results.csv"), ("studio_on_models", "studio_models_results.csv"),
               ("bench_tiled", "tiled_results.csv"), ("bench_drag", "drag_results.csv"),
               ("bench_tiled_simplify", "tiled_simplify_results.csv"), ("bench_tiled_edit", "tiled_edit_results.csv"),
               ("bench_studio_level", "studio_level_results.csv")]


def long_rows(out_dir):
    """results.csv's rows: [source, section, row, column, value] for every figure of every stage's CSV."""
    sources = [("bench_editing", section, rows) for section, rows in read_editing(os.path.join(out_dir, "editing_results.csv")).items()]
    sources += [(name, "", read_csv(os.path.join(out_dir, file))) for name, file in STAGE_FILES]
    # The paper's own Table 1, which the manual quotes beside ours.
    paper = []
    for model, (points, ssps, roi, times) in PAPER_TABLE1.items():
        for order, (editing, diffusion) in zip(["linear", "quadric", "cubic"], times):
            if editing is not None:
                paper.append({"model": model, "order": order, "points": str(points), "ssps": str(ssps), "roi_ssps": str(roi),
                              "editing_ssps_s": str(editing), "diffusion_s": str(diffusion)})
    sources.append(("paper_table1", "", paper))
    return [[source, section, str(i), column, value]
            for source, section, rows in sources for i, r in enumerate(rows) for column, value in r.items()]


def write_long_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["source", "section", "row", "column", "value"])
        w.writerows(rows)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--merge":
        write_long_csv(os.path.join(sys.argv[2], "results.csv"), long_rows(sys.argv[2]))
        return
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    out_dir, build_dir = sys.argv[1], sys.argv[2]
    editing = read_editing(os.path.join(out_dir, "editing_results.csv"))
    simplification = read_csv(os.path.join(out_dir, "simplification_results.csv"))
    upsampling = read_csv(os.path.join(out_dir, "upsampling_results.csv"))
    curvature = read_csv(os.path.join(out_dir, "curvature_results.csv"))
    memory = read_csv(os.path.join(out_dir, "memory_results.csv"))
    if not editing["table1"]:
        sys.exit(f"make_results.py: no editing results in {out_dir} (run bench_editing first)")
    threads = os.environ.get("BENCHMARK_THREADS", str(os.cpu_count()))
    quick = os.environ.get("BENCHMARK_QUICK") == "1"

    out = ["# Benchmark results", ""]
    out.append("Written by `bash scripts/run_benchmarks.sh`" + (" --quick (small sizes, one repetition)" if quick else "")
               + ": times are medians over repeated runs (min-max in the per-stage files). Details of every stage: "
               "[editing](editing_results.md), [up-sampling](upsampling_results.md), "
               "[SSPs](simplification_results.md), [curvature](curvature_results.md), [normals](normals_results.md), "
               "[detail scaling](scaling_results.md), [details](details_results.md), [memory](memory_results.md), "
               "[raw scans](raw_scan_results.md), [Python](python_results.md), [drags at scale](drag_results.md), [studio](studio_results.md) ([on CGAL's models](studio_models_results.md), [on a scan larger than it edits whole](studio_level_results.md)), "
               "[tiled runs on Dask](tiled_results.md) ([sample points](tiled_simplify_results.md), "
               "[edit](tiled_edit_results.md)).\n")
    table(out, ["machine", ""], machine_facts(build_dir, threads))
    table1_section(out, editing)
    peers_section(out, editing, simplification, upsampling, curvature,
                  read_csv(os.path.join(out_dir, "curvature_accuracy.csv")))
    scaling_section(out, editing, memory, os.path.join(out_dir, "scaling.png"))
    solver_section(out, editing)
    memory_section(out, read_csv(os.path.join(out_dir, "details_results.csv")), simplification, curvature)
    with open(os.path.join(out_dir, "RESULTS.md"), "w") as f:
        f.write("\n".join(out))
    write_long_csv(os.path.join(out_dir, "results.csv"), long_rows(out_dir))
    print(f"wrote {out_dir}/RESULTS.md, {out_dir}/results.csv and {out_dir}/scaling.png")


if __name__ == "__main__":
    main()
