"""Runs the README's quick starts as a newcomer would after the demo command, and checks what they wrote.

Usage: readme_quick_starts.py BUILD_DIR

Each shell block after a `<!-- quick start: NAME -->` marker runs with bash -euo pipefail in a fresh folder that
holds what the repository's root holds for it: `build` (BUILD_DIR), `doc`, and `point-detail-demo/` from the
program's demo, as `scripts/run_demo.sh` makes it. The blocks' `bash scripts/...` lines build targets, which the
test command has built already; they are skipped, and every other line runs as written.
"""
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
EXPECTED = {  # what each quick start must leave behind
    "program": ["tentacle_details.ply", "tentacle_details.png", "tentacle_scaled.ply", "tentacle_bent.ply",
                "tentacle_bent.png", "tentacle_view.png"],
    "C++": [],
    "Python": ["tentacle_relief.ply", "tentacle_lifted.ply"],
}


def quick_starts(readme):
    blocks = dict(re.findall(r"<!-- quick start: (\S+) -->\n```sh\n(.*?)```", readme, re.S))
    if sorted(blocks) != sorted(EXPECTED):
        sys.exit(f"readme_quick_starts.py: the README's quick starts are {sorted(blocks)}, expected {sorted(EXPECTED)}")
    return {name: "\n".join(line for line in body.splitlines() if not line.startswith("bash scripts/")) + "\n"
            for name, body in blocks.items()}


def main(build):
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        blocks = quick_starts(f.read())
    with tempfile.TemporaryDirectory() as folder:
        os.symlink(os.path.abspath(build), os.path.join(folder, "build"))
        os.symlink(os.path.join(ROOT, "doc"), os.path.join(folder, "doc"))
        subprocess.run([os.path.join(build, "src", "point-detail"), "-q", "demo", "-o", "point-detail-demo"],
                       cwd=folder, check=True)
        failed = []
        for name, script in blocks.items():
            run = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=folder, capture_output=True, text=True)
            missing = [f for f in EXPECTED[name] if not os.path.isfile(os.path.join(folder, f))]
            if run.returncode != 0 or missing:
                failed.append(name)
                print(f"quick start {name}: exit status {run.returncode}, missing {missing}\n{run.stdout}{run.stderr}")
            else:
                print(f"quick start {name}: ran; {run.stdout.strip()[-200:]}")
        if "Python" not in failed:
            check = ("import cgal_ext, numpy as np\n"
                     "a = cgal_ext.read_points('point-detail-demo/tentacle.ply').points\n"
                     "b = cgal_ext.read_points('tentacle_lifted.ply').points\n"
                     "tip = np.argmin(a[:, 0])\n"
                     "assert np.allclose(b[tip] - a[tip], [0, 0, 0.3], atol=1e-12), b[tip] - a[tip]\n"
                     # Fixed points next to the region follow it a little (the diffusion is continuous); farther
                     # ones keep their bits.
                     "assert np.array_equal(a[a[:, 2] < 0.3], b[a[:, 2] < 0.3]), 'a point far from the region moved'\n")
            env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"))
            if subprocess.run([sys.executable, "-c", check], cwd=folder, env=env).returncode != 0:
                failed.append("Python (the tip lifted by 0.3, the rest in place)")
    if failed:
        sys.exit(f"readme_quick_starts.py: failed: {', '.join(failed)}")


if __name__ == "__main__":
    main(sys.argv[1])
